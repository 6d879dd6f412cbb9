"""From a campaign spec to the exact inputs of every run (deterministic, order-free).

Run ids, grid points and replicates
-----------------------------------
With G grid points (the Cartesian product of the base-scenario list and every ``{grid = [...]}``
field, in file order, the last axis varying fastest) and ``runs`` replicates per point, run id
``r = g * runs + j`` (``g`` the grid index, ``j`` the replicate). Chunks never straddle grid points,
so a chunk is homogeneous in every swept value. ``[campaign] first_replicate = s`` makes replicate ``j``
the ``s + j``-th of the stream (paired random sampling): a campaign of replicates ``s .. s + runs - 1``
runs exactly those runs of a campaign with ``s + runs`` replicates (a later block, in its own directory).

Seeds and samples
-----------------
Every random number of run ``r`` comes from :class:`numpy.random.SeedSequence` keyed by the campaign
seed and ``key = j`` (``paired = true``: common random numbers, the same fault profile at every grid
point, which is what a paired comparison of two controllers needs) or ``key = r`` (``paired = false``):

* scenario seed (``simulation.seed``) = 31 bits of ``SeedSequence(seed, spawn_key=(key, 0))``;
* sampled field ``path`` = one draw from ``default_rng(SeedSequence(seed, spawn_key=(key, 1, crc32(path))))``.

Nothing depends on which other runs exist, the order they are computed in, or the chunking; adding
a sampled field does not change the values drawn for the others. :meth:`CampaignPlan.run_columns`
derives these numbers for a whole chunk at once (:mod:`formation_ftc.campaign.streams`: the same
``SeedSequence`` and ``PCG64`` integers as arrays), bit-identical to the per-run objects.

Quasi-Monte Carlo (``[campaign] sampling = "sobol"`` or ``"lhs"``)
------------------------------------------------------------------
The random fields (every sampler except ``grid``, in file order) share one point ``u`` of a
``d``-dimensional unit cube design, ``d`` = number of random fields; field ``m`` takes the value of
its distribution's inverse CDF at ``u[m]`` (uniform: ``low + (high - low) u``; loguniform: the same in
``log``; normal: the (truncated) normal quantile; integer: ``low + floor((high - low + 1) u)``;
choice: the item whose cumulative-weight interval holds ``u``). The design is drawn once from
``SeedSequence(seed, spawn_key=(2**32 - 1, 2 or 3))`` and row ``key`` (the replicate, or the run id
when ``paired = false``) belongs to the run:

* ``"sobol"``: scrambled Sobol' sequence (:class:`scipy.stats.qmc.Sobol`, Owen scrambling). Row ``key``
  is the ``key``-th point of the sequence, so a run's values depend only on (seed, key, the list of
  random fields), never on how many runs there are; the first ``2**m`` replicates form a
  ``(t, m, d)``-net (use a power of two for ``runs`` to get its balance).
* ``"lhs"``: Latin hypercube (:class:`scipy.stats.qmc.LatinHypercube`, one point per stratum
  ``[k/n, (k+1)/n)`` of every dimension) over ``n = runs`` rows (``n_runs`` when unpaired). A run's
  values depend on (seed, key, fields, ``n``): changing ``--runs`` draws a new hypercube.

Scenario seeds stay pseudo-random (``run_seed``). Unlike ``"random"``, adding or removing a random
field changes the design, so the values of the others change too.
"""

from __future__ import annotations

import copy
import json
import math
import zlib
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, overload

import numpy as np

from formation_ftc.campaign import streams
from formation_ftc.campaign.spec import (
    MAX_RUNS,
    CampaignError,
    CampaignSpec,
    Choice,
    Grid,
    Integer,
    LogUniform,
    Normal,
    Sampler,
    Uniform,
    spec_hash,
)
from formation_ftc.config import loader
from formation_ftc.config.base import field_bounds, field_info

__all__ = [
    "RunInputs",
    "RunColumns",
    "Chunk",
    "ChunkList",
    "CampaignPlan",
    "run_seed",
    "run_seeds",
    "draw_value",
    "draw_values",
    "value_from_unit",
    "qmc_design",
]

_QMC_SPAWN = 2**32 - 1  # spawn-key entry no run key reaches (run ids are below 2**32 - 1)
_QMC_KINDS = {"sobol": 2, "lhs": 3}


@dataclass(frozen=True)
class RunInputs:
    """What defines run ``run_id``: its grid point, replicate, seed and the values set by the campaign."""

    run_id: int
    grid_index: int
    replicate: int
    seed: int
    base: str
    values: dict[str, Any] = field(default_factory=dict)  # dotted path -> value (grid and sampled)


@dataclass(frozen=True, slots=True)
class Chunk:
    """Runs ``start .. stop-1`` of one grid point: one vmap batch and one Parquet file."""

    chunk_id: int
    grid_index: int
    start: int
    stop: int

    @property
    def run_ids(self) -> list[int]:
        return list(range(self.start, self.stop))

    def __len__(self) -> int:
        return self.stop - self.start


class ChunkList(Sequence[Chunk]):
    """Chunks of a plan by id, each made when it is read: a campaign of millions of chunks is planned
    in a ``range`` (or 8 bytes per pending chunk), not in one object per chunk."""

    def __init__(self, plan: CampaignPlan, ids: range | np.ndarray):
        self.plan, self.ids = plan, ids

    def __len__(self) -> int:
        return len(self.ids)

    @overload
    def __getitem__(self, k: int) -> Chunk: ...

    @overload
    def __getitem__(self, k: slice) -> ChunkList: ...

    def __getitem__(self, k: int | slice) -> Chunk | ChunkList:
        if isinstance(k, slice):
            return ChunkList(self.plan, self.ids[k])
        return self.plan.chunk(int(self.ids[k]))


@dataclass(frozen=True)
class RunColumns:
    """The :class:`RunInputs` of many runs as columns (``values``: dotted path -> one value per run)."""

    run_id: np.ndarray  # int64
    grid_index: np.ndarray  # int64
    replicate: np.ndarray  # int64
    seed: np.ndarray  # int64, the scenario seeds
    base: np.ndarray  # int64 index into the plan's base names
    values: dict[str, list[Any]]

    def __len__(self) -> int:
        return int(self.run_id.shape[0])

    def row(self, k: int, base_names: list[str]) -> RunInputs:
        """Run ``k`` (position in the columns) as :class:`RunInputs` (grid values copied per run)."""
        vals = {p: copy.deepcopy(v[k]) for p, v in self.values.items()}  # scalars: the same object
        return RunInputs(
            int(self.run_id[k]),
            int(self.grid_index[k]),
            int(self.replicate[k]),
            int(self.seed[k]),
            base_names[int(self.base[k])],
            vals,
        )

    def rows(self, base_names: list[str]) -> list[RunInputs]:
        return [self.row(k, base_names) for k in range(len(self))]


def run_seed(campaign_seed: int, key: int) -> int:
    """31-bit scenario seed of the run with sampling key ``key`` (replicate or run id)."""
    ss = np.random.SeedSequence(campaign_seed, spawn_key=(int(key), 0))
    return int(ss.generate_state(1, dtype=np.uint32)[0] >> 1)


def draw_value(sampler: Sampler, campaign_seed: int, key: int) -> Any:
    """The value of a random field for sampling key ``key`` (independent stream per field path)."""
    ss = np.random.SeedSequence(
        campaign_seed, spawn_key=(int(key), 1, zlib.crc32(sampler.path.encode()))
    )
    return sampler.draw(np.random.default_rng(ss))


def draw_values(sampler: Sampler, campaign_seed: int, keys: list[int] | np.ndarray) -> list[Any]:
    """:func:`draw_value` for many sampling keys at once (the same numbers).

    The generator states of all keys are derived at once (:mod:`formation_ftc.campaign.streams`);
    distributions that map the first double of the stream (uniform, loguniform, normal, weighted
    choice) are evaluated as arrays, the others draw from each run's generator. The first keys are
    also drawn the per-run way and compared (once per process and sampler): any difference falls back
    to per-run generators.
    """
    crc = zlib.crc32(sampler.path.encode())
    ks = np.asarray(keys, dtype=np.int64).reshape(-1)
    if ks.size and streams.available() and ks.min() >= 0 and ks.max() <= 0xFFFFFFFF:
        values = sampler.from_first_double(streams.first_doubles(campaign_seed, ks, (1, crc)))
        if values is None:
            values = [sampler.draw(g) for g in streams.generators(campaign_seed, ks, (1, crc))]
        tag = repr(sampler)
        if tag in _CHECKED_SAMPLERS or all(
            _same(values[n], draw_value(sampler, campaign_seed, int(ks[n])))
            for n in range(min(4, ks.size))
        ):
            _CHECKED_SAMPLERS.add(tag)
            return values
    rngs = [
        np.random.default_rng(np.random.SeedSequence(campaign_seed, spawn_key=(int(k), 1, crc)))
        for k in ks.tolist()
    ]
    return sampler.draw_many(rngs)


def run_seeds(campaign_seed: int, keys: list[int] | np.ndarray) -> np.ndarray:
    """:func:`run_seed` of many sampling keys (int64 array; the same numbers)."""
    ks = np.asarray(keys, dtype=np.int64).reshape(-1)
    if ks.size and streams.available() and ks.min() >= 0 and ks.max() <= 0xFFFFFFFF:
        return streams.run_seeds(campaign_seed, ks)
    return np.array([run_seed(campaign_seed, int(k)) for k in ks.tolist()], dtype=np.int64)


def all_numbers(values: list[Any]) -> bool:
    """Every value an int or float (not a bool): a check per distinct type, not per value."""
    return all(
        issubclass(t, int | float) and not issubclass(t, bool) for t in set(map(type, values))
    )


#: samplers (by repr) whose array evaluation matched the per-run draws in this process
_CHECKED_SAMPLERS: set[str] = set()


def _same(a: Any, b: Any) -> bool:
    return type(a) is type(b) and (
        a == b or (isinstance(a, float) and math.isnan(a) and math.isnan(b))
    )


def value_from_unit(sampler: Sampler, u: float) -> Any:
    """The value of ``sampler``'s distribution at quantile ``u`` in [0, 1) (its inverse CDF)."""
    u = min(max(float(u), 0.0), np.nextafter(1.0, 0.0))
    if isinstance(sampler, Uniform | LogUniform | Normal):  # their draw maps one uniform double
        return sampler.from_first_double(np.asarray([u]))[0]
    if isinstance(sampler, Integer):
        return int(
            min(sampler.low + math.floor((sampler.high - sampler.low + 1) * u), sampler.high)
        )
    if isinstance(sampler, Choice):
        w = np.asarray(sampler.weights or [1.0] * len(sampler.values), float)
        edges = np.cumsum(w) / np.sum(w)
        k = min(int(np.searchsorted(edges, u, side="right")), len(sampler.values) - 1)
        return copy.deepcopy(sampler.values[k])
    if isinstance(sampler, Grid):
        raise TypeError("grid values are assigned by grid index, not drawn")
    raise TypeError(
        f"no quasi-Monte Carlo mapping for {type(sampler).__name__}"
    )  # pragma: no cover


#: most numbers (rows x random fields) of a quasi-Monte Carlo design: 32 MiB, about 100 MiB while SciPy
#: builds it (random sampling has no such limit: its values are derived per chunk)
MAX_DESIGN_VALUES = 2**22


def _design_length(kind: str, n: int) -> int:
    """Rows :func:`qmc_design` builds for ``n`` keys: the next power of two for Sobol', ``n`` for LHS."""
    return 2 ** max(0, math.ceil(math.log2(max(n, 1)))) if kind == "sobol" else n


def qmc_design(kind: str, d: int, n: int, campaign_seed: int) -> np.ndarray:
    """Rows ``0 .. n-1`` (at least) of the ``d``-dimensional ``kind`` design ("sobol" or "lhs") in [0, 1)^d.

    Sobol': the first ``2**ceil(log2 n)`` points of the scrambled sequence (a prefix of one infinite
    sequence: row ``k`` does not depend on ``n``). LHS: exactly ``n`` rows, one per stratum.
    """
    from scipy.stats import qmc

    if kind not in _QMC_KINDS:
        raise CampaignError(
            f"campaign.sampling: unknown quasi-Monte Carlo design {kind!r} (sobol, lhs)"
        )
    rng = np.random.default_rng(
        np.random.SeedSequence(campaign_seed, spawn_key=(_QMC_SPAWN, _QMC_KINDS[kind]))
    )
    cls = qmc.Sobol if kind == "sobol" else qmc.LatinHypercube
    try:
        engine = cls(d, scramble=True, rng=rng)
    except TypeError:  # pragma: no cover - SciPy < 1.15 names the generator ``seed``
        engine = cls(d, scramble=True, seed=rng)
    if kind == "sobol":
        return engine.random_base2(int(math.log2(_design_length(kind, n))))
    return engine.random(n)


def _walk(tree: Any, path: str) -> tuple[bool, Any, str]:
    """(exists, node, where it stopped) for a dotted path through dicts and lists."""
    node = tree
    done: list[str] = []
    for part in path.split("."):
        try:
            if isinstance(node, Mapping):
                node = node[part]
            elif isinstance(node, list | tuple):
                node = node[int(part)]
            else:
                return False, node, ".".join(done)
        except (KeyError, ValueError, IndexError):
            return False, node, ".".join(done)
        done.append(part)
    return True, node, path


def _materialize(raw: dict[str, Any], dump: Mapping[str, Any], path: str) -> None:
    """Copy from the validated ``dump`` the part of ``path`` missing in ``raw`` (defaults, list rows),
    so that :func:`loader.set_dotted` can set it in place."""
    node: Any = raw
    ref: Any = dump
    for part in path.split(".")[:-1]:
        if isinstance(node, list):
            k = int(part)
            node, ref = node[k], ref[k]
            continue
        if part not in node:
            node[part] = copy.deepcopy(ref[part])
            return
        node, ref = node[part], ref[part]


def _schema_bounds(method: str, path: str, scenario: Any = None) -> list[tuple[Any, str, Any]]:
    """Numeric bounds (``(bound, relation, test)``, :func:`~formation_ftc.config.base.field_bounds`)
    the method's schema declares for the field at ``path`` (list
    elements inherit the bounds of their list's field items when declared there). A composed
    ``scenario`` (the validated base) gives each slot's section, whose model declares them."""
    from formation_ftc.registry import get_method

    try:
        model: Any = get_method(method).schema
    except KeyError:
        return []
    parts = path.split(".")
    section = getattr(scenario, "section", None)
    if callable(section) and section(parts[0]) is not None:
        # a composed slot: its component's section
        model, parts = type(section(parts[0])), parts[1:]
    info = field_info(model, ".".join(parts))
    return [] if info is None else field_bounds(info)


def _describe_dump(node: Any) -> str:
    if isinstance(node, Mapping):
        return "fields: " + ", ".join(map(str, node)) if node else "no fields"
    if isinstance(node, list | tuple):
        return f"a list of {len(node)} item(s) (index 0..{len(node) - 1})"
    return f"a value ({node!r})"


#: runs whose inputs :meth:`CampaignPlan.validate_all` derives at once (bounds the memory of planning)
VALIDATION_BLOCK = 2**14


class _Validation:
    """What :meth:`CampaignPlan.validate_all` gathers block by block: bound violations (first run and
    count), non-finite values, the runs holding each numeric field's extremes and one run per structure."""

    def __init__(self, plan: CampaignPlan):
        self.plan = plan
        self.numeric = [s.path for s in plan.samplers if s.numeric]
        self.other = [s.path for s in plan.samplers if not s.numeric]
        self.bases = range(len(plan.base_names))
        self.bounds = {
            (p, b): _schema_bounds(plan.methods[b], p, plan.base_scenarios[b])
            for p in self.numeric
            for b in self.bases
        }
        # (path, base, bound) -> [run id, value, runs in all]
        self.violations: dict[tuple[str, int, int], list[Any]] = {}
        self.non_finite: dict[tuple[str, int], tuple[int, Any]] = {}  # -> (run id, value)
        self.lowest: dict[tuple[str, int], tuple[float, RunInputs]] = {}
        self.highest: dict[tuple[str, int], tuple[float, RunInputs]] = {}
        self.structures: dict[str, RunInputs] = {}

    def add(self, cols: RunColumns) -> None:
        names = self.plan.base_names
        sels = {b: np.flatnonzero(cols.base == b) for b in self.bases}
        for path in self.numeric:
            vals = np.array(cols.values[path], dtype=np.float64)
            for b, sel in sels.items():
                if not sel.size:
                    continue
                for i, (bound, _, test) in enumerate(self.bounds[path, b]):
                    bad = sel[np.flatnonzero(~np.asarray(test(vals[sel], bound), dtype=bool))]
                    if bad.size:
                        first = [int(cols.run_id[bad[0]]), vals[bad[0]], 0]
                        self.violations.setdefault((path, b, i), first)[2] += bad.size
                v = vals[sel]
                finite = np.isfinite(v)
                if not finite.all():
                    k = int(sel[np.flatnonzero(~finite)[0]])
                    self.non_finite.setdefault((path, b), (int(cols.run_id[k]), vals[k]))
                    continue
                lo, hi = int(sel[int(np.argmin(v))]), int(sel[int(np.argmax(v))])
                if (path, b) not in self.lowest or vals[lo] < self.lowest[path, b][0]:
                    self.lowest[path, b] = (vals[lo], cols.row(lo, names))
                if (path, b) not in self.highest or vals[hi] > self.highest[path, b][0]:
                    self.highest[path, b] = (vals[hi], cols.row(hi, names))
        for b, sel in sels.items():  # one run per structure (base and non-numeric values)
            for k in (sel[:1] if not self.other else sel).tolist():
                key = names[b] + json.dumps(
                    {p: cols.values[p][k] for p in self.other}, sort_keys=True, default=str
                )
                if key not in self.structures:
                    self.structures[key] = cols.row(k, names)

    def errors(self) -> list[str]:
        """The bound and finiteness errors, field by field and base by base."""
        out = []
        for path in self.numeric:
            for b in self.bases:
                for i, (bound, op, _) in enumerate(self.bounds[path, b]):
                    if (path, b, i) in self.violations:
                        r, v, n = self.violations[path, b, i]
                        out.append(
                            f"run {r}: {path} = {v!r} violates {path} {op} {bound} ({n} run(s) in all)"
                        )
                if (path, b) in self.non_finite:
                    r, v = self.non_finite[path, b]
                    out.append(f"run {r}: {path} = {v!r} is not finite")
        return out

    @property
    def chosen(self) -> dict[int, RunInputs]:
        """Run id -> inputs of the runs validated in full: extremes of the finite fields, one per structure."""
        out: dict[int, RunInputs] = {}
        for key in self.lowest.keys() - self.non_finite.keys():
            for _, row in (self.lowest[key], self.highest[key]):
                out.setdefault(row.run_id, row)
        for row in self.structures.values():
            out.setdefault(row.run_id, row)
        return out


class CampaignPlan:
    """A validated campaign: base scenarios, grid, samplers, run ids and chunks. Picklable (sent to
    worker processes and Dask workers with every chunk)."""

    def __init__(
        self, spec: CampaignSpec, base_dir: Path | None = None, drop_missing_traces: bool = False
    ):
        self.spec = spec
        meta = spec.campaign
        self.name = meta.name
        self.seed = meta.seed
        self.runs = meta.runs
        self.chunk_size = meta.chunk_size
        self.paired = meta.paired
        self.first_replicate = meta.first_replicate
        self.sampling = meta.sampling
        self._design: np.ndarray | None = None  # quasi-Monte Carlo rows, built on first use
        self.base_names = spec.bases
        loaded = [self._load_base(name, base_dir) for name in self.base_names]
        self.base_raws: list[dict[str, Any]] = [raw for raw, _ in loaded]
        # validated (with the campaign's overrides)
        self.base_scenarios: list[Any] = [s for _, s in loaded]
        self.methods: list[str] = [s.scenario.method for s in self.base_scenarios]
        dumps = [s.model_dump(mode="json") for s in self.base_scenarios]
        self.samplers = spec.samplers()
        self.grid_samplers = [s for s in self.samplers if isinstance(s, Grid)]  # kind "grid"
        self.random_samplers = [s for s in self.samplers if s.kind != "grid"]
        for s in self.samplers:
            for name, raw, dump in zip(self.base_names, self.base_raws, dumps, strict=True):
                ok, node, where = _walk(dump, s.path)
                if not ok:
                    raise CampaignError(
                        f"sample.{s.path}: dotted path does not exist in base scenario {name!r} "
                        f"(method {raw['scenario']['method']}); at {where or '<top level>'} it has "
                        f"{_describe_dump(node)}"
                    )
                if isinstance(node, Mapping):
                    raise CampaignError(
                        f"sample.{s.path}: names a whole table of {name!r}; sample one "
                        f"field ({_describe_dump(node)})"
                    )
                _materialize(raw, dump, s.path)
        self.grid_shape = ([len(self.base_names)] if len(self.base_names) > 1 else []) + [
            len(s.values) for s in self.grid_samplers
        ]
        self.n_grid = int(np.prod(self.grid_shape)) if self.grid_shape else 1
        self.n_runs = self.n_grid * self.runs
        self.chunks_per_point = -(-self.runs // self.chunk_size)
        self.n_chunks = self.n_grid * self.chunks_per_point
        self._check_design_size()
        bad = [r for r in spec.traces.runs if r >= self.n_runs]
        if bad and drop_missing_traces:
            # --runs made the campaign smaller: keep the traces that exist
            kept = [r for r in spec.traces.runs if r < self.n_runs]
            spec = spec.model_copy(update={"traces": spec.traces.model_copy(update={"runs": kept})})
            self.spec = spec
        elif bad:
            raise CampaignError(
                f"traces.runs: run id(s) {bad} do not exist (run ids are 0..{self.n_runs - 1})"
            )
        self.hash = spec_hash(spec, self.base_raws)
        self._check_extremes()

    # ------------------------------------------------------------------------------ base scenarios
    def _load_base(self, name: str, base_dir: Path | None) -> tuple[dict[str, Any], Any]:
        """(raw, validated scenario) of a base, with the campaign's overrides; a relative path is
        looked up next to the campaign file first."""
        local = None if base_dir is None or Path(name).is_absolute() else base_dir / name
        if local is not None and local.is_file():
            raw, source = loader.read_raw(local)
        else:
            try:
                raw, source = loader.read_raw(name)
            except loader.ScenarioError as exc:
                raise CampaignError(f"campaign.base: {exc}") from None
        try:
            raw = loader.apply_overrides(raw, self.spec.overrides)
            scenario = loader.validate(raw, f"{source} with the campaign's [overrides]")
        except loader.ScenarioError as exc:
            raise CampaignError(f"campaign.base {name!r}: {exc}") from None
        return raw, scenario

    def _check_extremes(self) -> None:
        """Every bound of every sampler must validate on every base, before any run."""
        for s in self.samplers:
            for v in s.extremes():
                for name, raw in zip(self.base_names, self.base_raws, strict=True):
                    r = copy.deepcopy(raw)
                    loader.set_dotted(r, s.path, v)
                    try:
                        loader.validate(r, f"base scenario {name!r}")
                    except loader.ScenarioError as exc:
                        raise CampaignError(
                            f"sample.{s.path}: value {v!r} ({s.describe()}) is outside what the scenario "
                            f"allows:\n{exc}"
                        ) from None

    # --------------------------------------------------------------------------------- run inputs
    def grid_point(self, g: int) -> tuple[int, dict[str, Any]]:
        """(base index, {path: value} of the grid fields) of grid index ``g``."""
        if not self.grid_shape:
            return 0, {}
        idx = list(np.unravel_index(g, self.grid_shape))
        b = int(idx.pop(0)) if len(self.base_names) > 1 else 0
        return b, {
            s.path: copy.deepcopy(s.values[int(k)])
            for s, k in zip(self.grid_samplers, idx, strict=True)
        }

    def run_inputs(self, run_id: int) -> RunInputs:
        """The inputs of run ``run_id`` (see :meth:`run_columns`)."""
        return self.run_columns([run_id]).row(0, self.base_names)

    def run_inputs_many(self, run_ids: list[int]) -> list[RunInputs]:
        """:meth:`run_inputs` of many runs (see :meth:`run_columns`)."""
        return self.run_columns(run_ids).rows(self.base_names)

    def run_columns(self, run_ids: list[int] | np.ndarray) -> RunColumns:
        """The inputs of many runs as columns, derived per field for all runs at once: vectorised seeds
        and draws (the numbers of :func:`run_seed` and :func:`draw_value`), grid values looked up per
        grid point."""
        ids = np.asarray(run_ids, dtype=np.int64).reshape(-1)
        if ids.size and (ids.min() < 0 or ids.max() >= self.n_runs):
            bad = int(ids[(ids < 0) | (ids >= self.n_runs)][0])
            raise CampaignError(f"run id {bad} does not exist (0..{self.n_runs - 1})")
        g, j = np.divmod(ids, self.runs)
        j = j + self.first_replicate
        keys = j if self.paired else ids
        points = {int(x): self.grid_point(int(x)) for x in np.unique(g)}
        values: dict[str, list[Any]] = {}
        if len(points) == 1:  # one grid point (a chunk): constant columns
            ((b0, grid0),) = points.values()
            base = np.full(ids.size, b0, dtype=np.int64)
            for gs in self.grid_samplers:
                values[gs.path] = [grid0[gs.path]] * ids.size
        else:
            g_list = g.tolist()
            base = np.array([points[x][0] for x in g_list], dtype=np.int64)
            for gs in self.grid_samplers:
                values[gs.path] = [points[x][1][gs.path] for x in g_list]
        if self.sampling == "random":
            for s in self.random_samplers:
                values[s.path] = draw_values(s, self.seed, keys) if ids.size else []
        elif self.random_samplers:
            design = self.design()
            for m, s in enumerate(self.random_samplers):
                values[s.path] = [value_from_unit(s, u) for u in design[keys, m].tolist()]
        seeds = run_seeds(self.seed, keys) if ids.size else np.zeros(0, np.int64)
        return RunColumns(ids, g, j, seeds, base, {s.path: values[s.path] for s in self.samplers})

    def _design_rows(self) -> int:
        """Rows of the quasi-Monte Carlo design: one per sampling key."""
        return self.runs if self.paired else self.n_runs

    def design(self) -> np.ndarray:
        """The quasi-Monte Carlo unit-cube design of this campaign (rows indexed by sampling key)."""
        if self._design is None:
            self._design = qmc_design(
                self.sampling, len(self.random_samplers), self._design_rows(), self.seed
            )
        return self._design

    def _check_design_size(self) -> None:
        """Refuse a quasi-Monte Carlo design of more than :data:`MAX_DESIGN_VALUES` numbers: it is held
        whole in memory (by this process and every worker), unlike random samples, derived per chunk."""
        d = len(self.random_samplers)
        if self.sampling == "random" or not d:
            return
        rows = _design_length(self.sampling, self._design_rows())
        if rows * d <= MAX_DESIGN_VALUES:
            return
        most = MAX_DESIGN_VALUES // d  # design rows, i.e. sampling keys (Sobol': a power of two)
        most = 2 ** int(math.log2(most)) if self.sampling == "sobol" else most
        allowed = most if self.paired else most // self.n_grid
        fits = f"1 <= runs <= {allowed:,} here" if allowed else "no --runs fits this grid"
        raise CampaignError(
            f"--runs / campaign.runs = {self.runs:,}: the {self.sampling} design would hold {rows:,} rows x {d} random "
            f"fields = {rows * d * 8 / 2**20:,.0f} MiB, over the {MAX_DESIGN_VALUES * 8 // 2**20} MiB a design may "
            f'take ({fits}); or use sampling = "random" (up to {MAX_RUNS:,} runs per grid point)'
        )

    def scenario_raw(self, inputs: RunInputs) -> dict[str, Any]:
        raw = copy.deepcopy(self.base_raws[self.base_names.index(inputs.base)])
        for path, v in inputs.values.items():
            loader.set_dotted(raw, path, v)
        loader.set_dotted(raw, "simulation.seed", inputs.seed)
        return raw

    def scenario(self, inputs: RunInputs):
        """The validated scenario of one run (ScenarioError names the run and field)."""
        try:
            return loader.validate(self.scenario_raw(inputs), f"run {inputs.run_id}")
        except loader.ScenarioError as exc:
            shown = ", ".join(f"{p} = {v!r}" for p, v in inputs.values.items())
            raise CampaignError(
                f"run {inputs.run_id} ({shown}): sampled scenario is invalid:\n{exc}"
            ) from None

    def validate_all(self, run_ids: list[int] | np.ndarray | None = None) -> None:
        """Validate every run (default: all) before anything runs, without building each scenario.

        Numeric fields are checked as arrays against the bounds the scenario schema declares for them
        (the message names the field, the run id and the value); then the scenario is validated in
        full for one run per structure (base and non-numeric values) and for the runs holding the
        smallest and the largest value of every numeric field (cross-field rules see the extremes).
        The runs are derived :data:`VALIDATION_BLOCK` at a time: validating millions of runs takes the
        memory of one block.
        """
        seen = _Validation(self)
        for block in self._run_id_blocks(run_ids):
            seen.add(self.run_columns(block))
        errors = seen.errors()
        for i in sorted(seen.chosen.values(), key=lambda x: x.run_id):
            if len(errors) >= 3:
                break
            try:
                self.scenario(i)
            except CampaignError as exc:
                errors.append(str(exc))
        if errors:
            raise CampaignError(
                "samples outside what the scenario allows (nothing was run):\n"
                + "\n".join(errors[:3])
            )

    def _run_id_blocks(self, run_ids: list[int] | np.ndarray | None) -> Iterator[np.ndarray]:
        """``run_ids`` (default: every run) in blocks of at most :data:`VALIDATION_BLOCK`."""
        if run_ids is None:
            for a in range(0, self.n_runs, VALIDATION_BLOCK):
                yield np.arange(a, min(a + VALIDATION_BLOCK, self.n_runs), dtype=np.int64)
            return
        ids = np.asarray(run_ids, dtype=np.int64).reshape(-1)
        for a in range(0, ids.size, VALIDATION_BLOCK):
            yield ids[a : a + VALIDATION_BLOCK]

    # ------------------------------------------------------------------------------------ chunks
    def chunks(self, done: set[int] | frozenset[int] = frozenset()) -> ChunkList:
        """Every chunk in id order, except those in ``done`` (made on access, see :class:`ChunkList`)."""
        if not done:
            return ChunkList(self, range(self.n_chunks))
        finished = np.fromiter(done, dtype=np.int64, count=len(done))
        return ChunkList(self, np.setdiff1d(np.arange(self.n_chunks, dtype=np.int64), finished))

    def chunk(self, chunk_id: int) -> Chunk:
        g, c = divmod(int(chunk_id), self.chunks_per_point)
        start = g * self.runs + c * self.chunk_size
        return Chunk(int(chunk_id), g, start, min(start + self.chunk_size, (g + 1) * self.runs))

    # ------------------------------------------------------------------------------- description
    def input_columns(self) -> dict[str, bool]:
        """``input:<path>`` column -> numeric? (non-numeric values are stored as JSON text)."""
        return {f"input:{s.path}": s.numeric for s in self.samplers}

    def swept(self) -> list[str]:
        """Columns that identify a grid point (scenario first when several bases)."""
        cols = ["scenario"] if len(self.base_names) > 1 else []
        return cols + [f"input:{s.path}" for s in self.grid_samplers]

    def sampled(self) -> list[str]:
        return [f"input:{s.path}" for s in self.random_samplers]

    def summary(self) -> dict[str, Any]:
        return dict(
            name=self.name,
            bases=self.base_names,
            methods=self.methods,
            runs_per_point=self.runs,
            grid_points=self.n_grid,
            total_runs=self.n_runs,
            chunk_size=self.chunk_size,
            chunks=self.n_chunks,
            seed=self.seed,
            paired=self.paired,
            sampling=self.sampling,
            samplers={s.path: s.describe() for s in self.samplers},
        )
