"""Campaign files: a base scenario plus sampled or swept fields (TOML, validated like scenarios).

A campaign file looks like::

    [campaign]
    name = "cw-pd-gains"
    description = "PD gains vs loss of effectiveness"
    base = "cw-pd-fault"              # built-in scenario name or TOML path; a list = one more grid axis
    runs = 100                        # runs per grid point (total runs when nothing is swept)
    seed = 2026                       # campaign seed: run seeds and samples derive from it
    chunk_size = 25                   # runs per vmap batch
    metrics = ["max_position_error"]  # metrics to keep (empty: all the method returns)
    paired = true                     # same samples/seed for the same replicate at every grid point
    sampling = "random"               # or "sobol" / "lhs" (quasi-Monte Carlo, see campaign.sampling)

    [overrides]                       # fixed changes to the base scenario (dotted path = value)
    "simulation.horizon" = 100.0

    [sample]                          # dotted path = distribution or sweep
    "controller.kp" = {dist = "uniform", low = 1.0, high = 3.0}
    "controller.kd" = {grid = [10.0, 30.0]}
    "plant.mass.0" = {dist = "normal", mean = 100.0, std = 5.0, low = 80.0}

    [traces]                          # optional decimated time histories for a few runs
    runs = [0, 1]
    every = 10

Samplers: ``{dist = "uniform", low, high}``, ``{dist = "normal", mean, std[, low, high]}`` (truncated
when bounds are given, drawn by inverse CDF), ``{dist = "loguniform", low, high}`` (0 < low < high),
``{dist = "integer", low, high}`` (inclusive), ``{choice = [...][, weights = [...]]}`` (random) and
``{grid = [...]}`` (swept: every value gets ``runs`` runs). Keys may be quoted dotted paths or nested
TOML tables; both are flattened to dotted paths.
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any, Literal

import numpy as np
from pydantic import Field, ValidationError, field_validator, model_validator
from scipy import stats

from formation_ftc.config.base import StrictModel, validation_message
from formation_ftc.errors import InputError

__all__ = [
    "CampaignError",
    "Sampler",
    "Uniform",
    "Normal",
    "LogUniform",
    "Integer",
    "Choice",
    "Grid",
    "parse_sampler",
    "CampaignMeta",
    "TraceSpec",
    "CampaignSpec",
    "builtin_campaigns",
    "load_campaign",
    "spec_hash",
]

_SAMPLER_KEYS = {"dist", "grid", "choice"}


#: most runs per grid point [-]
MAX_RUNS = 10_000_000


class CampaignError(InputError):
    """A campaign that cannot be read, validated, stored or executed; the message names the field."""


# ----------------------------------------------------------------------------------------- samplers
@dataclass(frozen=True)
class Sampler:
    """A sampled or swept field. ``draw(rng)`` returns one value; ``extremes()`` the values that
    bound the support (validated against the scenario schema before any run)."""

    path: str

    kind = "random"  # "random" (drawn per run) or "grid" (swept)

    def draw(self, rng: np.random.Generator) -> Any:  # pragma: no cover - always overridden
        """One value drawn with ``rng`` (subclasses define the distribution)."""
        return NotImplemented

    def draw_many(self, rngs: list[np.random.Generator]) -> list[Any]:
        """One value per generator: the same numbers as ``[draw(r) for r in rngs]`` (subclasses
        vectorise the expensive part)."""
        return [self.draw(r) for r in rngs]

    def from_first_double(self, d: np.ndarray) -> list[Any] | None:
        """The values ``draw`` returns for fresh generators whose first ``random()`` is ``d`` (one per
        run), or None when a draw is not a function of the first double alone (then each run's
        generator draws; see :mod:`formation_ftc.campaign.streams`)."""
        return None

    def extremes(self) -> list[Any]:
        return []

    @property
    def numeric(self) -> bool:
        return True

    def describe(self) -> str:  # pragma: no cover - overridden
        return self.kind


def _finite(path: str, name: str, v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise CampaignError(f"sample.{path}: {name} must be a number, got {v!r}")
    if not math.isfinite(float(v)):
        raise CampaignError(f"sample.{path}: {name} must be finite, got {v!r}")
    return float(v)


def _need_bounds(s: Any, ok: bool, need: str) -> None:
    """Raise the error naming ``s``'s field when its ``low``/``high`` bounds fail ``need``."""
    if not ok:
        raise CampaignError(f"sample.{s.path}: {need}, got low = {s.low}, high = {s.high}")


@dataclass(frozen=True)
class Uniform(Sampler):
    low: float = 0.0
    high: float = 1.0

    def __post_init__(self):
        _need_bounds(self, self.low < self.high, "uniform needs low < high")

    def draw(self, rng):
        return float(rng.uniform(self.low, self.high))

    def from_first_double(self, d):
        # Generator.uniform(low, high) = low + (high - low) * random()
        return (float(self.low) + (float(self.high) - float(self.low)) * d).tolist()

    def extremes(self):
        return [self.low, self.high]

    def describe(self):
        return f"uniform[{self.low:g}, {self.high:g}]"


@dataclass(frozen=True)
class LogUniform(Sampler):
    low: float = 1.0
    high: float = 10.0

    def __post_init__(self):
        _need_bounds(self, 0 < self.low < self.high, "loguniform needs 0 < low < high")

    def draw(self, rng):
        return float(math.exp(rng.uniform(math.log(self.low), math.log(self.high))))

    def from_first_double(self, d):
        lo, hi = math.log(self.low), math.log(self.high)
        # math.exp: the same libm as draw
        return [math.exp(x) for x in (lo + (hi - lo) * d).tolist()]

    def extremes(self):
        return [self.low, self.high]

    def describe(self):
        return f"loguniform[{self.low:g}, {self.high:g}]"


@dataclass(frozen=True)
class Normal(Sampler):
    mean: float = 0.0
    std: float = 1.0
    low: float | None = None
    high: float | None = None

    def __post_init__(self):
        if not self.std > 0:
            raise CampaignError(f"sample.{self.path}: normal needs std > 0, got std = {self.std}")
        lo = -math.inf if self.low is None else self.low
        hi = math.inf if self.high is None else self.high
        _need_bounds(self, lo < hi, "truncated normal needs low < high")

    def draw(self, rng):
        return self._from_uniform(np.asarray([rng.uniform()]))[0]

    def draw_many(self, rngs):
        # one uniform per run from its own stream, the inverse CDF evaluated once for all of them
        return self._from_uniform(np.asarray([r.uniform() for r in rngs]))

    def from_first_double(self, d):
        return self._from_uniform(np.asarray(d, dtype=np.float64))  # uniform() = 0 + 1 * random()

    def _from_uniform(self, u: np.ndarray) -> list[float]:
        if self.low is None and self.high is None:
            return [float(v) for v in self.mean + self.std * stats.norm.ppf(u)]
        a = -np.inf if self.low is None else (self.low - self.mean) / self.std
        b = np.inf if self.high is None else (self.high - self.mean) / self.std
        return [float(v) for v in stats.truncnorm.ppf(u, a, b, loc=self.mean, scale=self.std)]

    def extremes(self):
        return [v for v in (self.low, self.high) if v is not None]

    def describe(self):
        s = f"normal(mean {self.mean:g}, std {self.std:g})"
        if self.low is not None or self.high is not None:
            s += (
                f" truncated to [{self.low if self.low is not None else '-inf'}, "
                f"{self.high if self.high is not None else 'inf'}]"
            )
        return s


@dataclass(frozen=True)
class Integer(Sampler):
    low: int = 0
    high: int = 1

    def __post_init__(self):
        _need_bounds(self, self.low <= self.high, "integer needs low <= high")

    def draw(self, rng):
        return int(rng.integers(self.low, self.high, endpoint=True))

    def extremes(self):
        return [self.low, self.high]

    def describe(self):
        return f"integer[{self.low}, {self.high}]"


@dataclass(frozen=True)
class _Values(Sampler):
    """A sampler over listed ``values`` (:class:`Choice`, :class:`Grid`)."""

    values: tuple = ()

    def extremes(self):
        return list(self.values)

    @property
    def numeric(self) -> bool:
        return all(isinstance(v, int | float) and not isinstance(v, bool) for v in self.values)


@dataclass(frozen=True)
class Choice(_Values):
    weights: tuple | None = None

    def draw(self, rng):
        p = None if self.weights is None else np.asarray(self.weights) / np.sum(self.weights)
        return copy.deepcopy(self.values[int(rng.choice(len(self.values), p=p))])

    def from_first_double(self, d):
        if self.weights is None:
            return None  # Generator.choice without p draws a bounded integer
        # Generator.choice(n, p=p): the cumulative weights searched with one random() (side="right")
        cdf = (np.asarray(self.weights) / np.sum(self.weights)).astype(np.float64).cumsum()
        cdf /= cdf[-1]
        return [copy.deepcopy(self.values[int(k)]) for k in cdf.searchsorted(d, side="right")]

    def describe(self):
        return f"choice of {len(self.values)}"


@dataclass(frozen=True)
class Grid(_Values):
    kind = "grid"

    def draw(self, rng):  # pragma: no cover - grid values are assigned, not drawn
        raise TypeError("grid values are assigned by grid index")

    def describe(self):
        return f"grid of {len(self.values)}"


def parse_sampler(path: str, spec: Mapping[str, Any]) -> Sampler:
    """``{dist = ...}`` / ``{grid = [...]}`` / ``{choice = [...]}`` -> :class:`Sampler` (errors name the field)."""
    if not isinstance(spec, Mapping):
        raise CampaignError(
            f'sample.{path}: expected a table like {{dist = "uniform", low = 0, high = 1}}, '
            f"{{grid = [...]}} or {{choice = [...]}}, got {spec!r}"
        )
    keys = set(spec)
    if len(keys & _SAMPLER_KEYS) != 1:
        raise CampaignError(
            f"sample.{path}: give exactly one of dist, grid, choice (got {sorted(keys)})"
        )

    def allowed(*names):
        if extra := keys - set(names):
            raise CampaignError(
                f"sample.{path}: unknown key(s) {sorted(extra)}; allowed: {list(names)}"
            )

    if "grid" in spec or "choice" in spec:
        key = "grid" if "grid" in spec else "choice"
        allowed(key) if key == "grid" else allowed("choice", "weights")
        values = spec[key]
        if not isinstance(values, list) or not values:
            raise CampaignError(f"sample.{path}: {key} must be a non-empty list, got {values!r}")
        if key == "grid":
            return Grid(path, tuple(values))
        w = spec.get("weights")
        if w is not None:
            if not isinstance(w, list) or len(w) != len(values):
                raise CampaignError(
                    f"sample.{path}: weights must be a list of {len(values)} numbers"
                )
            w = tuple(_finite(path, "weights", x) for x in w)
            if any(x < 0 for x in w) or sum(w) <= 0:
                raise CampaignError(
                    f"sample.{path}: weights must be >= 0 with a positive sum, got {list(w)}"
                )
        return Choice(path, tuple(values), w)

    dist = spec["dist"]
    if dist not in _DISTS:
        raise CampaignError(
            f"sample.{path}: unknown dist {dist!r}; use uniform, normal, loguniform or integer "
            f"(or grid = [...], choice = [...])"
        )
    cls, params, n_required = _DISTS[dist]
    allowed("dist", *params)
    if missing := [n for n in params[:n_required] if n not in spec]:
        raise CampaignError(f"sample.{path}: {dist} distribution needs {', '.join(missing)}")
    if cls is Integer:
        for n in params:
            if isinstance(spec[n], bool) or not isinstance(spec[n], int):
                raise CampaignError(
                    f"sample.{path}: integer {n} must be an integer, got {spec[n]!r}"
                )
        return Integer(path, int(spec["low"]), int(spec["high"]))
    values = {n: _finite(path, n, spec[n]) for n in ("low", "high", "mean", "std") if n in spec}
    return cls(path, *(values.get(n) for n in params))


#: dist -> (sampler, its parameters in the order it takes them, how many of them are required)
_DISTS: dict[str, tuple[type[Sampler], tuple[str, ...], int]] = {
    "uniform": (Uniform, ("low", "high"), 2),
    "loguniform": (LogUniform, ("low", "high"), 2),
    "normal": (Normal, ("mean", "std", "low", "high"), 2),
    "integer": (Integer, ("low", "high"), 2),
}


def _flatten(table: Mapping[str, Any], prefix: str = "", stop=lambda v: False) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in table.items():
        path = f"{prefix}.{k}" if prefix else str(k)
        if isinstance(v, Mapping) and not stop(v):
            out.update(_flatten(v, path, stop))
        else:
            out[path] = v
    return out


# ------------------------------------------------------------------------------------------ schema
class CampaignMeta(StrictModel):
    name: str = Field(description="Campaign name.")
    description: str = Field("", description="One line shown by `formation-ftc campaign list`.")
    base: str | list[str] = Field(
        description="Base scenario (built-in name or TOML path); a list adds a "
        "grid axis over scenarios."
    )
    runs: int = Field(
        ge=1,
        le=MAX_RUNS,
        description="Runs per grid point (total runs when nothing is swept), "
        "at most 10 million [-].",
    )
    seed: int = Field(
        0, ge=0, description="Campaign seed; run seeds and samples derive from it [-]."
    )
    chunk_size: int = Field(32, ge=1, le=100_000, description="Runs per vmap batch [-].")
    first_replicate: int = Field(
        0,
        ge=0,
        le=MAX_RUNS,
        description="Replicate j of this campaign is replicate first_replicate + j of the seed's "
        "stream: a later block of the same replicates in another directory (paired random "
        "sampling only) [-].",
    )
    metrics: list[str] = Field(default_factory=list, description="Metrics to keep (empty: all).")
    paired: bool = Field(
        True,
        description="Same samples and seed for replicate j at every grid point "
        "(common random numbers) [-].",
    )
    sampling: Literal["random", "sobol", "lhs"] = Field(
        "random",
        description="How the random fields are drawn: 'random' (independent pseudo-random "
        "draws), 'sobol' (scrambled Sobol' quasi-Monte Carlo points) or 'lhs' (Latin hypercube); see "
        "formation_ftc.campaign.sampling.",
    )

    @model_validator(mode="after")
    def _block(self):
        if self.first_replicate and not (self.paired and self.sampling == "random"):
            raise ValueError(
                "campaign.first_replicate: a later block of replicates needs paired = true and "
                'sampling = "random" (a quasi-Monte Carlo design is one block)'
            )
        return self

    @field_validator("base")
    @classmethod
    def _base_nonempty(cls, v):
        if isinstance(v, list) and (not v or len(set(v)) != len(v)):
            raise ValueError(
                "campaign.base: a list of base scenarios must be non-empty and without repeats"
            )
        return v


class TraceSpec(StrictModel):
    runs: list[int] = Field(
        default_factory=list, description="Run ids whose time histories are kept [-]."
    )
    every: int = Field(1, ge=1, description="Keep every k-th record of the scenario's records [-].")
    variables: list[str] = Field(
        default_factory=list, description="Dataset variables to keep (empty: all)."
    )

    @field_validator("runs")
    @classmethod
    def _nonneg(cls, v):
        if any(r < 0 for r in v):
            raise ValueError("traces.runs: run ids are >= 0")
        return sorted(set(v))


class CampaignSpec(StrictModel):
    campaign: CampaignMeta
    overrides: dict[str, Any] = Field(
        default_factory=dict, description="Fixed dotted-path overrides of the base."
    )
    sample: dict[str, Any] = Field(
        default_factory=dict, description="Dotted path -> sampler table."
    )
    traces: TraceSpec = TraceSpec()

    @field_validator("overrides", mode="before")
    @classmethod
    def _flatten_overrides(cls, v):
        if not isinstance(v, Mapping):
            raise ValueError("overrides must be a table of dotted.path = value")
        return _flatten(v)

    @field_validator("sample", mode="before")
    @classmethod
    def _flatten_sample(cls, v):
        if not isinstance(v, Mapping):
            raise ValueError("sample must be a table of dotted.path = {dist = ...}")
        return _flatten(v, stop=lambda t: bool(set(t) & _SAMPLER_KEYS))

    @model_validator(mode="after")
    def _samplers(self):
        for path, s in self.sample.items():
            parse_sampler(path, s)  # raises CampaignError (a ValueError) naming the field
            if path == "simulation.seed":
                raise ValueError(
                    "sample.simulation.seed: the run seed is set from the campaign seed and "
                    "the run id; sample another field"
                )
            if path in self.overrides:
                raise ValueError(
                    f"sample.{path}: also fixed in [overrides]; give it in one place only"
                )
        if "simulation.seed" in self.overrides:
            raise ValueError("overrides.simulation.seed: the run seed is set from campaign.seed")
        return self

    # -- derived
    def samplers(self) -> list[Sampler]:
        return [parse_sampler(p, s) for p, s in self.sample.items()]

    @property
    def bases(self) -> list[str]:
        b = self.campaign.base
        return list(b) if isinstance(b, list) else [b]


# --------------------------------------------------------------------------------------- loading
def builtin_campaigns() -> dict[str, str]:
    """Name -> TOML text of every built-in campaign."""
    from formation_ftc.config.loader import builtin_tomls

    return builtin_tomls(resources.files("formation_ftc.campaign") / "builtin")


def load_campaign(
    name_or_path: str | Path | Mapping[str, Any],
    *,
    runs: int | None = None,
    chunk_size: int | None = None,
) -> tuple[CampaignSpec, Path | None]:
    """Built-in name, TOML path or raw dict -> ``(CampaignSpec, directory of the file or None)``.

    ``runs``/``chunk_size`` override the file's values (the command-line options).
    """
    base_dir: Path | None = None
    if isinstance(name_or_path, Mapping):
        raw, source = copy.deepcopy(dict(name_or_path)), "<dict>"
    else:
        from formation_ftc.config.loader import read_named_toml

        if isinstance(name_or_path, str) and (not name_or_path.strip() or "\x00" in name_or_path):
            raise CampaignError(f"invalid campaign name or path {name_or_path!r}")
        raw, source = read_named_toml(
            name_or_path, "campaign", builtin_campaigns, "built-in campaign", error=CampaignError
        )
        if source == str(Path(name_or_path)):  # a file: its base scenarios may be relative to it
            base_dir = Path(name_or_path).resolve().parent
    meta = raw.get("campaign")
    if isinstance(meta, dict):
        if runs is not None:
            meta["runs"] = runs
        if chunk_size is not None:
            meta["chunk_size"] = chunk_size
    try:
        spec = CampaignSpec.model_validate(raw)
    except ValidationError as exc:
        raise CampaignError(
            validation_message(exc, f"{source}: invalid campaign", "unknown field", root="")
        ) from None
    except (ValueError, TypeError, ArithmeticError, RecursionError) as exc:
        raise CampaignError(f"{source}: {exc}") from None
    return spec, base_dir


def _canonical(obj: Any) -> str:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), default=str)


def spec_hash(spec: CampaignSpec, base_raws: list[dict[str, Any]]) -> str:
    """SHA-256 of the campaign spec and the *content* of its base scenarios (not their names only)."""
    h = hashlib.sha256()
    dump = spec.model_dump(mode="json")
    if dump["campaign"].get("sampling") == "random":
        # the default: same hash as before the option existed
        del dump["campaign"]["sampling"]
    h.update(_canonical(dump).encode())
    for raw in base_raws:
        h.update(_canonical(raw).encode())
    return h.hexdigest()
