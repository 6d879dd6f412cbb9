"""League definitions: which methods, on which truth, under which faults, scored how.

A league is a TOML file (built-in ones in ``league/data/``)::

    [league]        name, version, description, battery, seeds, quick_seeds, seed, horizon, chunk_size
    [league.requirement]   metric, max, units       pass/fail of every run
    [league.initial_error] field, std, units        desired slot + N(0, std^2) per axis and spacecraft
    [league.onset]         low, high                fault onset, uniform [s]
    [truth]         the plant table shared by every method (e.g. type = "orbital-truth")
    [sensors]       the sensors shared by every method (a method may replace them)
    [actuator]      the actuator table shared by every method (type = "fault-battery")
    [[levels]]      name, saturation                actuator levels (per-axis limit [N or N m]; inf: none)
    [[evaluations]] score signals (e.g. type = "formation-scores")
    [[metrics]]     scores computed inside every run
    [[methods]]     name, scenario, label, reference     one per method

Each method's ``scenario`` is a partial composed scenario (``league/data/<league>/<method>.toml``) that
gives what belongs to the law -- controller, network, reference (the on-board orbit model), estimator,
supervisor, the sensors it needs and its own time step -- and nothing about the truth, the faults or
the scoring, which the league fills in alike for every method.
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import tomllib
from importlib import resources
from pathlib import Path
from typing import Any, Literal

from pydantic import Field, ValidationError, field_validator, model_validator

from formation_ftc.config.base import StrictModel
from formation_ftc.errors import InputError

__all__ = [
    "LeagueError",
    "LeagueSpec",
    "MethodEntry",
    "Level",
    "builtin_leagues",
    "load_league",
    "method_scenario",
    "league_hash",
    "TuneBounds",
    "TuneSection",
    "method_tune",
]

#: the slots a method's own file may fill (the league owns plant, actuator, evaluations and metrics)
METHOD_SLOTS = ("reference", "sensors", "network", "estimator", "supervisor", "controller")


class LeagueError(InputError):
    """A league definition that cannot run (exit code 2); the message names the entry."""


#: the metric an STL requirement adds to every run: the robustness of its negation, ``-rho(phi)`` [units
#: of the atoms], so that a run passes when it is <= 0 (``rho(phi) >= 0``) and lower is better
STL_VIOLATION = "stl_violation"


class Requirement(StrictModel):
    metric: str = Field(
        description="Metric the requirement is stated on (one of the league's metrics)."
    )
    max: float = Field(gt=0, description="Largest value that passes [metric units].")
    units: str = Field("1", description="Units of `max` (UDUNITS).")
    stl: str | None = Field(
        None,
        description="The requirement as a signal temporal logic formula over recorded signals "
        "(docs/requirements.md), e.g. 'F[0,300](G(shape_error <= 1))': every run records "
        "stl_violation, minus its robustness.",
    )
    verdict: Literal["metric", "stl"] = Field(
        "metric",
        description="What passes a run: 'metric' (metric <= max) or 'stl' (robustness >= 0).",
    )

    @model_validator(mode="after")
    def _stl(self):
        if self.stl is not None:
            from formation_ftc.sim.stl import parse

            parse(self.stl)  # StlError (a ValueError) names the position
        elif self.verdict == "stl":
            raise ValueError("league.requirement.verdict = 'stl' needs league.requirement.stl")
        return self


def requirement_of(league: dict[str, Any]) -> tuple[str, float, str]:
    """``(metric, max, units)`` that pass a run of the ``[league]`` table ``league`` (a dict read from
    a definition): the stated metric and its bound, or, with ``verdict = "stl"``,
    (:data:`STL_VIOLATION`, 0, the units).

    Examples
    --------
    >>> requirement_of({"requirement": {"metric": "e", "max": 1.0, "units": "m"}})
    ('e', 1.0, 'm')
    >>> requirement_of({"requirement": {"metric": "e", "max": 1.0, "units": "m", "stl": "G(e <= 1)",
    ...                                 "verdict": "stl"}})
    ('stl_violation', 0.0, 'm')
    """
    req = league["requirement"]
    if req.get("verdict", "metric") == "stl":
        return STL_VIOLATION, 0.0, str(req.get("units", ""))
    return str(req["metric"]), float(req["max"]), str(req.get("units", ""))


class InitialError(StrictModel):
    """Either ``seed_field``: the plant draws its own initial dispersion (its deviations in [truth]) from
    a seed the league samples per replicate -- one sampled number per run, however many spacecraft; or
    ``field`` + ``std``: each component of a per-spacecraft list is sampled around its [truth] value."""

    seed_field: str | None = Field(
        None,
        description="Dotted path of the plant's dispersion seed, e.g. 'plant.dispersion_seed'.",
    )
    field: str | None = Field(
        None,
        description="Dotted path of the plant's (N, 3) initial list, e.g. "
        "'plant.initial_position'.",
    )
    std: float | None = Field(
        None, ge=0, description="Standard deviation per component [m or deg] (with field)."
    )
    units: str = Field("m", description="Units of `std`.")

    @model_validator(mode="after")
    def _one_mode(self):
        if (self.seed_field is None) == (self.field is None):
            raise ValueError("league.initial_error: give either seed_field, or field and std")
        if self.field is not None and self.std is None:
            raise ValueError("league.initial_error.std: required with field")
        return self


class Onset(StrictModel):
    field: str = Field("actuator.onset", description="Dotted path of the fault onset [s].")
    low: float = Field(ge=0, description="Earliest onset [s].")
    high: float = Field(ge=0, description="Latest onset [s].")

    @model_validator(mode="after")
    def _order(self):
        if self.high < self.low:
            raise ValueError(f"league.onset: high = {self.high} < low = {self.low}")
        return self


class StepCheckSection(StrictModel):
    """The step-convergence check run before each method's campaign (:mod:`formation_ftc.league.step_check`)."""

    enabled: bool = Field(True, description="Run the check (false: every method keeps its own dt).")
    case: str = Field("bias", description="Fault case of the check cell (a battery case name).")
    level: str | None = Field(
        None, description="Level of the check cell (default: the first level)."
    )
    tolerance: float = Field(
        0.02,
        gt=0,
        lt=1,
        description="Largest relative change of any score when the step halves [-].",
    )
    max_halvings: int = Field(
        3, ge=0, le=6, description="How many times the check may halve a method's step [-]."
    )


class LeagueMeta(StrictModel):
    name: str = Field(description="League name.")
    version: str = Field(
        description="League definition version (bump on any change of its content)."
    )
    description: str = Field("", description="One line shown by `formation-ftc league list`.")
    kind: str = Field(
        "translational", description="'translational' or 'attitude' (what the scores mean)."
    )
    battery: str = Field(description="Name of the fault battery (league/data/battery-NAME.toml).")
    seeds: int = Field(
        100, ge=1, le=100_000, description="Monte Carlo seeds per cell (full league) [-]."
    )
    quick_seeds: int = Field(10, ge=1, le=100_000, description="Seeds per cell with --quick [-].")
    seed: int = Field(
        0, ge=0, description="League seed: every run's seed and draws derive from it [-]."
    )
    horizon: float = Field(gt=0, description="Simulated time of every run [s].")
    chunk_size: int = Field(64, ge=1, le=100_000, description="Runs per vmap batch [-].")
    settle_start: float = Field(
        ge=0, description="Start of the scoring window (after the acquisition) [s]."
    )
    requirement: Requirement
    initial_error: InitialError
    onset: Onset
    trace_seed: int = Field(
        0, ge=0, description="Seed index whose time histories the report plots [-]."
    )
    step_check: StepCheckSection = Field(
        default_factory=StepCheckSection,
        description="Step-convergence check of every method before its campaign.",
    )
    trace_cases: list[str] = Field(
        ["none", "loe-50"],
        description="Fault cases whose time histories (trace seed, first level) are kept for the "
        "report's plot.",
    )


class Level(StrictModel):
    name: str = Field(description="Actuator level name (e.g. 'unsaturated', 'limited').")
    saturation: float | None = Field(
        None,
        gt=0,
        description="Per-axis limit of every actuator [N or N m]; leave it out for no limit.",
    )
    note: str = Field("", description="Why this limit (shown in the report).")
    navigation: Literal["raw", "filtered"] = Field(
        "raw",
        description="What every law flies on at this level: 'raw' (the sensors' measurement) or "
        "'filtered' (the league's [navigation_filter]; a method's residual FDI navigates instead, "
        "with fly_on_filter; an observer reads the filter's estimate too).",
    )
    method_fields_from: str = Field(
        "",
        description="The level whose [levels.<name>] fields of the method files apply here (e.g. "
        "'limited' for 'limited-filtered': the same thrusters, the same flight knowledge); default: "
        "this level's own name.",
    )


class MethodEntry(StrictModel):
    name: str = Field(description="Method name in the leaderboard.")
    scenario: str = Field(
        description="The method's partial composed scenario, relative to the league file."
    )
    label: str = Field("", description="Long name shown in the report.")
    reference: str = Field(
        "", description="Where the law and its gains come from (docs/references.md)."
    )
    gain_rule: str = Field(
        "", description="How the paper's gains were carried to the league plant."
    )


class TuneBounds(StrictModel):
    low: float = Field(description="Smallest value the tuning may give the field [field units].")
    high: float = Field(description="Largest value [field units].")
    log: bool = Field(False, description="Search the field on a logarithmic scale (low > 0).")
    rebuild: bool = Field(
        False,
        description="The field is an input of its builder, not a leaf of the loop (e.g. Bryson's "
        "maxima, from which the LQR builder derives its Riccati gain): the runs are built again at "
        "every evaluation (derivative-free optimisers only; slower).",
    )


class TuneSection(StrictModel):
    """A method file's ``[tune]`` table: which of its numbers ``formation-ftc tune`` may choose."""

    fields: dict[str, TuneBounds | list[float]] = Field(
        min_length=1,
        description="Dotted field (e.g. 'controller.k') -> [low, high] or {low, high, log}.",
    )
    objective: str = Field("delta_v_total", description="League metric minimised.")
    statistic: Literal["mean", "median"] = Field(
        "mean", description="'mean' or 'median' over the training runs."
    )
    note: str = Field("", description="Why these fields and bounds.")

    @field_validator("fields")
    @classmethod
    def _bounds(cls, v):
        for path, b in v.items():
            slot, _, name = path.partition(".")
            if slot not in METHOD_SLOTS or not name or "." in name:
                raise ValueError(
                    f"{path}: give 'slot.field' of a slot the method owns "
                    f"({', '.join(METHOD_SLOTS)}), e.g. 'controller.k'"
                )
            if isinstance(b, list):
                if len(b) != 2:
                    raise ValueError(f"{path}: bounds [low, high], got {b}")
                b = TuneBounds(low=b[0], high=b[1])
            if not (math.isfinite(b.low) and math.isfinite(b.high) and b.low < b.high):
                raise ValueError(f"{path}: bounds [{b.low:g}, {b.high:g}] need low < high, finite")
            if b.log and b.low <= 0:
                raise ValueError(f"{path}: a log scale needs low > 0, got {b.low:g}")
            v[path] = b  # a [low, high] list as its bounds (same key: the dict keeps its order)
        return v


class LeagueSpec(StrictModel):
    league: LeagueMeta
    truth: dict[str, Any] = Field(description="The truth plant table shared by every method.")
    sensors: dict[str, Any] | None = Field(
        None, description="Default sensors (a method may replace them)."
    )
    actuator: dict[str, Any] = Field(
        description="The actuator table shared by every method (fault battery)."
    )
    levels: list[Level] = Field(min_length=1, description="Actuator levels.")
    evaluations: list[dict[str, Any]] = Field(default_factory=list, description="Score signals.")
    metrics: list[dict[str, Any]] = Field(
        min_length=1, description="Scores computed inside every run."
    )
    methods: list[MethodEntry] = Field(min_length=1, description="The methods ranked.")
    navigation_filter: dict[str, Any] | None = Field(
        None,
        description="The navigation filter of the 'filtered' levels (an [estimator] table, e.g. type "
        "= 'relative-navigation-filter' with the noise stated for the league's truth).",
    )
    _source: Path | None = None

    @field_validator("levels")
    @classmethod
    def _unique_levels(cls, v):
        names = [lv.name for lv in v]
        if len(set(names)) != len(names):
            raise ValueError(f"levels: duplicate names {names}")
        return v

    @model_validator(mode="after")
    def _consistent(self):
        names = [m.name for m in self.methods]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"methods: duplicate method names {dup}")
        req = self.league.requirement
        if req.stl is not None and STL_VIOLATION not in [m.get("name") for m in self.metrics]:
            violation = f"not ({req.stl})"
            self.metrics.append(
                {"name": STL_VIOLATION, "reduce": "stl", "formula": violation, "units": req.units}
            )
        metric_names = [str(m.get("name")) for m in self.metrics]
        if self.league.requirement.metric not in metric_names:
            raise ValueError(
                f"league.requirement.metric = {self.league.requirement.metric!r} is not one of the "
                f"league's metrics ({', '.join(metric_names)})"
            )
        names = [lv.name for lv in self.levels]
        for lv in self.levels:
            if lv.method_fields_from and lv.method_fields_from not in names:
                raise ValueError(
                    f"levels.{lv.name}.method_fields_from = {lv.method_fields_from!r}: not a level "
                    f"of the league ({', '.join(names)})"
                )
        filtered = [lv.name for lv in self.levels if lv.navigation == "filtered"]
        if filtered and self.navigation_filter is None:
            raise ValueError(
                f"levels {filtered}: navigation = 'filtered' needs the league's [navigation_filter] "
                "table (the filter every law flies on there)"
            )
        return self

    @property
    def source(self) -> Path:
        """The definition file (:func:`load_league` sets it)."""
        assert self._source is not None
        return self._source

    def method(self, name: str) -> MethodEntry:
        for m in self.methods:
            if m.name == name:
                return m
        raise LeagueError(
            f"method {name!r} is not in league {self.league.name!r} "
            f"(methods: {', '.join(m.name for m in self.methods)})"
        )


def builtin_files(prefix: str) -> dict[str, Path]:
    """The package's data files ``league/data/PREFIX-NAME.toml`` by NAME."""
    data = Path(str(resources.files("formation_ftc.league") / "data"))
    return {p.stem.removeprefix(f"{prefix}-"): p for p in sorted(data.glob(f"{prefix}-*.toml"))}


def builtin_leagues() -> dict[str, Path]:
    """Built-in league name -> definition file."""
    return builtin_files("league")


def _format(exc: ValidationError, source: str, dot: str = ": ", sep: str = "\n") -> str:
    """Every error of ``exc``: ``SOURCE: a.b: message`` (``dot`` between the source and the field's
    path), joined by ``sep``."""
    errors = [(".".join(map(str, err.get("loc", ()))), err.get("msg")) for err in exc.errors()]
    return sep.join(
        f"{source}{dot}{loc}: {msg}" if loc else f"{source}: {msg}" for loc, msg in errors
    )


def _toml(path: Path, where: str = "") -> dict[str, Any]:
    """The TOML file ``path`` as a dict; LeagueError ``WHERE PATH: not valid TOML: ...`` when it is not."""
    try:
        return tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise LeagueError(f"{where}{path}: not valid TOML: {exc}") from None


def load_league(name_or_path: str | Path) -> LeagueSpec:
    """A built-in league by name, or a league TOML file; every field validated (errors name it)."""
    known = builtin_leagues()
    path = known.get(str(name_or_path)) or Path(name_or_path)
    if not path.is_file():
        raise LeagueError(
            f"league {str(name_or_path)!r}: neither a built-in league "
            f"({', '.join(known) or 'none'}) nor a file"
        )
    try:
        spec = LeagueSpec.model_validate(_toml(path))
    except ValidationError as exc:
        raise LeagueError(_format(exc, str(path))) from None
    spec._source = path.resolve()
    for m in spec.methods:
        if not (spec._source.parent / m.scenario).is_file():
            raise LeagueError(
                f"{path}: methods[{m.name}].scenario = {m.scenario!r}: no such file next to the "
                "league definition"
            )
    return spec


def _method_raw(spec: LeagueSpec, method: MethodEntry) -> dict[str, Any]:
    path = spec.source.parent / method.scenario
    raw = _toml(path, f"method {method.name}: ")
    allowed = {"scenario", "simulation", "actuator", "tune", "levels", *METHOD_SLOTS}
    extra = sorted(set(raw) - allowed)
    if extra:
        raise LeagueError(
            f"method {method.name}: {path.name} sets {extra}; a method file gives only "
            f"{', '.join(sorted(allowed))} (the league owns the truth, faults and scores)"
        )
    if "tune" in raw:
        _check_tune(spec, method, raw, path)
    if "levels" in raw:
        _check_levels(spec, method, raw, path)
    return raw


#: slots whose fields a method may state per actuator level (flight knowledge, never the truth)
LEVEL_SLOTS = ("estimator", "supervisor", "controller")


def _check_levels(spec: LeagueSpec, method: MethodEntry, raw: dict[str, Any], path: Path) -> None:
    """The method file's ``[levels.<name>]`` tables: per actuator level, dotted fields of the method's
    own flight slots (e.g. ``"estimator.force_limit" = 0.2``: the thrust rating the method knows at
    that level). Each names a level of the league and a field of a slot the file sets."""
    where = f"method {method.name}: {path.name}: levels"
    names = [lv.name for lv in spec.levels]
    if not isinstance(raw["levels"], dict):
        raise LeagueError(f"{where}: a table of levels ([levels.<name>]), not {raw['levels']!r}")
    for level, fields in raw["levels"].items():
        if level not in names:
            raise LeagueError(f"{where}.{level}: not a level of the league ({', '.join(names)})")
        if not isinstance(fields, dict):
            raise LeagueError(f"{where}.{level}: a table of dotted fields, not {fields!r}")
        for fpath in fields:
            slot, _, name = str(fpath).partition(".")
            if slot not in LEVEL_SLOTS or not name or "." in name:
                raise LeagueError(
                    f"{where}.{level}.{fpath}: a level may set '<slot>.<field>' of the method's "
                    f"flight slots ({', '.join(LEVEL_SLOTS)}), not the truth or the league's scores"
                )
            if not isinstance(raw.get(slot), dict):
                raise LeagueError(
                    f"{where}.{level}.{fpath}: the method file has no [{slot}] to set {name} in"
                )


def _check_tune(spec: LeagueSpec, method: MethodEntry, raw: dict[str, Any], path: Path) -> None:
    """The method file's ``[tune]`` table checked: every field a number of the method's own section
    within its bounds, the objective a league metric (whether a field is a leaf of the built loop is
    checked when tuning, :func:`formation_ftc.league.tuning.build_problem`)."""
    where = f"method {method.name}: {path.name}: tune"
    try:
        tune = TuneSection.model_validate(raw["tune"])
    except ValidationError as exc:
        raise LeagueError(_format(exc, where)) from None
    for fpath, b in tune.fields.items():
        slot, _, name = fpath.partition(".")
        value = raw.get(slot, {}).get(name) if isinstance(raw.get(slot), dict) else None
        if value is None:
            raise LeagueError(
                f"{where}.fields.{fpath}: the method file sets no {name} in [{slot}] (a tuned field "
                "starts from the law's paper value, given in the file)"
            )
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise LeagueError(
                f"{where}.fields.{fpath}: {value!r} is not one number (a tunable field is a scalar gain)"
            )
        assert isinstance(b, TuneBounds)
        if not b.low <= float(value) <= b.high:
            raise LeagueError(
                f"{where}.fields.{fpath}: the paper value {value:g} lies outside the bounds "
                f"[{b.low:g}, {b.high:g}]"
            )
    metrics = [str(m.get("name")) for m in spec.metrics]
    if tune.objective not in metrics:
        raise LeagueError(
            f"{where}.objective = {tune.objective!r}: not a metric of league {spec.league.name} "
            f"({', '.join(metrics)})"
        )


def method_tune(spec: LeagueSpec, method: MethodEntry) -> TuneSection | None:
    """A method's validated ``[tune]`` table, or None when its file has none.

    Parameters
    ----------
    spec : LeagueSpec
        The league.
    method : MethodEntry
        One of its methods.

    Returns
    -------
    TuneSection or None
        Fields with bounds, objective and statistic.

    Raises
    ------
    LeagueError
        A table with an unknown key, bad bounds, a field the method file does not set as one number
        inside its bounds, or an objective that is not a league metric (the message names it).

    Examples
    --------
    >>> spec = load_league("translational")
    >>> sorted(method_tune(spec, spec.method("yang2013")).fields)
    ['controller.K1', 'controller.K2']
    """
    raw = _method_raw(spec, method)  # its [tune] table checked (_check_tune)
    return TuneSection.model_validate(raw["tune"]) if "tune" in raw else None


def method_scenario(
    spec: LeagueSpec,
    method: MethodEntry,
    level: Level,
    actuator_fields: dict[str, Any],
    network_fields: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """The full composed scenario of one cell: the league's truth, sensors, actuator (with the level's
    saturation and the fault case in ``actuator_fields``), evaluations and metrics, with the method's own
    slots (and time step) on top and its ``[levels.<level>]`` fields for this level (flight knowledge
    of the level, e.g. a thrust rating); ``network_fields`` turn the method's network into a link-fault one."""
    own = _method_raw(spec, method)
    sim = dict(own.get("simulation", {}))
    unknown_sim = sorted(set(sim) - {"dt", "record_every", "unroll"})
    if unknown_sim:
        raise LeagueError(
            f"method {method.name}: simulation.{unknown_sim[0]}: a method sets only its step "
            "(dt), record_every and unroll; the league sets the horizon and the seed"
        )
    raw: dict[str, Any] = {
        "scenario": {
            "name": f"league-{spec.league.name}-{method.name}",
            "method": "composed",
            "description": own.get("scenario", {}).get("description", method.label or method.name),
        },
        "simulation": {"horizon": spec.league.horizon, **sim},
        "plant": copy.deepcopy(spec.truth),
    }
    if spec.sensors is not None:
        raw["sensors"] = copy.deepcopy(spec.sensors)
    raw |= copy.deepcopy({slot: own[slot] for slot in METHOD_SLOTS if slot in own})
    known = own.get("levels", {}).get(level.method_fields_from or level.name, {})
    for fpath, value in known.items():  # the level's knowledge
        slot, _, name = fpath.partition(".")
        raw[slot][name] = copy.deepcopy(value)
    # the league's actuator, the method's structural options (allocation), the level and fault case
    raw["actuator"] = copy.deepcopy({**spec.actuator, **own.get("actuator", {}), **actuator_fields})
    if network_fields:
        if "network" not in raw:
            raise LeagueError(
                f"method {method.name} has no network: a communication fault does not apply"
            )
        raw["network"].update(copy.deepcopy(network_fields))
    if level.navigation == "filtered":
        _fly_filtered(spec, method, raw)
    raw["evaluations"] = copy.deepcopy(spec.evaluations)
    raw["metrics"] = copy.deepcopy(spec.metrics)
    return raw


def flies_filtered(spec: LeagueSpec, method: MethodEntry) -> bool:
    """Whether ``method`` can fly on the league's navigation filter: it has no estimator (the filter
    becomes its estimator), a residual FDI with a Kalman residual (which then navigates:
    ``fly_on_filter``) or an estimator that runs on a filter (a ``navigation`` table, e.g. the
    iterative learning observer). Any other estimator of its own does not."""
    est = _method_raw(spec, method).get("estimator")
    return (
        est is None
        or (est.get("type") == "residual-fdi" and est.get("residual") == "kalman")
        or _runs_on_filter(est)
    )


def _runs_on_filter(est: dict[str, Any]) -> bool:
    """Whether the estimator table's type takes a ``navigation`` filter table."""
    from formation_ftc.components._registry import component_type

    entry = component_type("estimator", str(est.get("type")))
    return entry is not None and "navigation" in entry.section.model_fields


def _fly_filtered(spec: LeagueSpec, method: MethodEntry, raw: dict[str, Any]) -> None:
    """A filtered level's cell: the law flies on the league's navigation filter (a method without an
    estimator; the controller's stated ``nominal_mass`` is the filter's), on its own residual FDI's
    Kalman filter (``fly_on_filter``) or on the league's filter that its observer also reads (the
    estimator's ``navigation`` table)."""
    if not flies_filtered(spec, method):
        raise LeagueError(
            f"method {method.name} has an estimator of its own: it cannot fly on the league's "
            "navigation filter (a filtered level does not apply to it)"
        )
    est = copy.deepcopy(spec.navigation_filter or {})
    if "estimator" in raw and _runs_on_filter(raw["estimator"]):
        raw["estimator"]["navigation"] = est  # the observer's masses where the filter states none
    elif "estimator" in raw:
        raw["estimator"]["fly_on_filter"] = True
    else:
        mass = raw.get("controller", {}).get("nominal_mass")
        if mass is not None and "nominal_mass" not in est:
            est["nominal_mass"] = copy.deepcopy(mass)
        raw["estimator"] = est


def league_hash(spec: LeagueSpec) -> str:
    """sha256 of the definition and of every method file (what the results directory is bound to)."""
    from formation_ftc.report.reproduce import to_jsonable  # non-finite floats as "inf", "nan"

    h = hashlib.sha256(json.dumps(to_jsonable(spec.model_dump()), sort_keys=True).encode())
    for m in spec.methods:
        h.update((spec.source.parent / m.scenario).read_bytes())
    return h.hexdigest()
