"""Run a league: one resumable campaign per method over every (fault case, actuator level) cell.

For each method the runner writes one full composed scenario per cell
(``DIR/<method>/cells/<case>--<level>.toml``, the exact input of those runs) and runs a campaign whose
grid axis is that list of scenarios and whose replicates are the Monte Carlo seeds. The replicates are
paired (common random numbers): replicate j has the same initial errors, fault onset and noise seed in
every cell and for every method, so differences between cells and between methods are not sampling
noise. Every cell of a method has the same structure, so one compiled program serves the whole method.

Everything is checked before the first run (unknown method or fault, a method that cannot drive the
league plant, metrics, the resource budgets of :mod:`formation_ftc.limits` applied to every method's
campaign and to their sum, the results directory): a bad league fails with exit code 2 and writes
nothing. ``league.json`` and the cell files are written atomically
(:func:`formation_ftc.atomic.atomic_write`), so a killed league resumes: run the same command again and only the missing chunks
run.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import json
import os
import re
import time
import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

import pandas as pd
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from formation_ftc import api
from formation_ftc.atomic import atomic_write
from formation_ftc.errors import InputError
from formation_ftc.league.definition import (
    STL_VIOLATION,
    LeagueError,
    LeagueSpec,
    MethodEntry,
    flies_filtered,
    league_hash,
    load_league,
    method_scenario,
)
from formation_ftc.limits import Budgets, check_run_steps, format_bytes, run_memory_bytes
from formation_ftc.progress import _Bars, _clock
from formation_ftc.runout import DISK_FULL, TMP_RE, existing_dir, oserror_as

__all__ = [
    "Cell",
    "LeagueOutcome",
    "plan_cells",
    "check_league_budgets",
    "run_league",
    "load_league_results",
    "LEAGUE_FILE",
    "LeagueRecord",
    "StepCheckRecord",
    "record_error",
    "METHOD_WORKER_BYTES",
    "Counter",
]

LEAGUE_FILE = "league.json"
#: the FDI scores the league adds to such a method's cells (fdi-scores evaluation, docs/league.md)
FDI_METRICS: tuple[dict[str, Any], ...] = (
    # time the fault was active before the first alarm (to the horizon when never detected) [s]
    {"name": "fdi_detection_delay", "signal": "fdi_pending", "reduce": "integral", "units": "s"},
    # 1: the fault is active and undetected at the horizon
    {"name": "fdi_missed", "signal": "fdi_missed", "reduce": "last"},
    # 1: an alarm while no fault was active
    {"name": "fdi_false_alarm", "signal": "fdi_false_alarm", "reduce": "max"},
    # 1: detected while the fault was active, isolating its (spacecraft, axis) channel
    {"name": "fdi_correct_isolation", "signal": "fdi_correct_isolation", "reduce": "max"},
    # time of the first alarm (NaN: none) and of the fault's onset (NaN: no fault) [s]
    {"name": "fdi_alarm_time", "signal": "fdi_detected", "reduce": "first", "threshold": 0.5,
     "units": "s"},
    {"name": "fdi_fault_time", "signal": "fault_active", "reduce": "first", "threshold": 0.5,
     "units": "s"},
)  # fmt: skip
#: the identification scores the league adds to a method whose estimator identifies faults
#: (identification-scores evaluation, docs/league.md)
#: the consistency of the navigation filter a law flies on (a filtered level, or a navigating FDI):
#: NEES and NIS of 6 states against their 95 % chi-square band (``navigation-consistency``)
NAVIGATION_METRICS: tuple[dict[str, Any], ...] = (
    # mean NEES over the run and the spacecraft (6 for a consistent filter) [-]
    {"name": "mean_nees", "signal": "nees", "reduce": "mean", "spacecraft": "mean"},
    # fraction of the samples whose NEES lies in the 95 % band (0.95 for a consistent filter) [-]
    {"name": "nees_in_band", "signal": "nees_in_band", "reduce": "mean", "spacecraft": "mean"},
    # the same of the filter's own normalised innovation squared [-]
    {"name": "nis_in_band", "signal": "nis_in_band", "reduce": "mean", "spacecraft": "mean"},
)

IDENTIFICATION_METRICS: tuple[dict[str, Any], ...] = (
    # |identified - true| effectiveness of the faulty channel at the horizon (NaN: not identified) [-]
    {"name": "id_effectiveness_error", "signal": "id_effectiveness_error", "reduce": "last"},
    # time after the onset the identified effectiveness was not within 10 % of the true one [s]
    {"name": "id_time_outside_10pct", "signal": "id_pending", "reduce": "integral", "units": "s"},
    # 1: a healthy channel identified outside 1 +- 0.1
    {"name": "id_false_identification", "signal": "id_false", "reduce": "max"},
)  # fmt: skip
#: what the league records of an HL supervisor's formation-level recovery (hierarchical supervisor)
FLFR_METRICS: tuple[dict[str, Any], ...] = (
    # longest time spent in FLFR [s] (0: FLFR never engaged)
    {"name": "flfr_time", "signal": "time_in_flfr", "reduce": "max", "units": "s"},
)
#: ... and on which spacecraft, where the law takes it from the FDI's isolation at run time
FLFR_SPACECRAFT_METRIC = {"name": "flfr_spacecraft", "signal": "flfr_spacecraft", "reduce": "last"}
#: the scores the step check leaves out: alarm times are on the step grid; identification errors are
#: small estimation errors (1e-4 against 3e-4 is no convergence verdict on the physics); an STL
#: robustness is a margin (its relative change is meaningless near 0; the signals it reads are
#: checked as scores); a filter's consistency is a noise statistic
_UNCHECKED = (*FDI_METRICS, *IDENTIFICATION_METRICS, *FLFR_METRICS, *NAVIGATION_METRICS)
_NOT_STEP_CHECKED = (*(m["name"] for m in _UNCHECKED), STL_VIOLATION)
#: memory of one method process of ``league run --workers N`` (JAX, its programs, one batch) [bytes]
METHOD_WORKER_BYTES = 1_200_000_000
_CHUNK_RE = re.compile(r"^chunk-(\d{6,})\.parquet$")


@dataclass(frozen=True)
class Cell:
    method: str
    case: str
    fault_kind: str
    level: str
    raw: dict  # the full composed scenario
    n_steps: int  # integration steps of one run

    @property
    def key(self) -> str:
        return f"{self.case}--{self.level}"


@dataclass
class LeagueOutcome:
    out_dir: Path
    n_runs: int
    n_failed: int
    seconds: float
    per_method: dict[str, float]

    def __str__(self) -> str:
        return f"{self.n_runs} runs ({self.n_failed} failed or diverged) in {self.out_dir} in {self.seconds:.1f} s"


def _battery(spec: LeagueSpec):
    from formation_ftc.league.battery import load_battery

    try:
        return load_battery(spec.league.battery)
    except ValueError as exc:
        raise LeagueError(f"league.battery = {spec.league.battery!r}: {exc}") from None


def plan_cells(spec: LeagueSpec, methods: list[str] | None = None) -> dict[str, list[Cell]]:
    """Every method's cells, each scenario validated (composition included) before anything runs.

    A case applies to a method when it means something for it (a communication fault needs a network,
    larger delays a delayed one). Every cell of a networked method uses the link-fault network (with no
    lost link outside the communication cases), so all its cells share one compiled program."""
    battery = _battery(spec)
    chosen = [spec.method(m) for m in methods] if methods else spec.methods
    quantity = "torque" if spec.league.kind == "attitude" else "force"
    out: dict[str, list[Cell]] = {}
    for m in chosen:
        network, delayed = _network_kind(spec, m)
        cells = []
        for case in battery.cases:
            if not case.applies_to(network=network, delayed=delayed):
                continue
            net_fields = case.network_fields(delayed=delayed) if network else None
            for level in spec.levels:
                if level.navigation == "filtered" and not flies_filtered(spec, m):
                    continue  # an estimator of its own: it flies on that (stated in the report)
                act = case.actuator_fields(saturation=level.saturation, quantity=quantity)
                raw = method_scenario(spec, m, level, act, net_fields)
                try:
                    raw = _with_fdi_scores(raw)
                    n_steps = int(api.load_scenario(raw).simulation.n_steps)
                except Exception as exc:  # noqa: BLE001 - any invalid cell: name it, exit code 2
                    raise LeagueError(
                        f"method {m.name} cannot run cell {case.name}/{level.name} of league "
                        f"{spec.league.name}: {exc}"
                    ) from None
                cells.append(Cell(m.name, case.name, case.kind, level.name, raw, n_steps))
        out[m.name] = cells
    return out


def _with_fdi_scores(raw: dict[str, Any]) -> dict[str, Any]:
    """A cell whose method flies a fault detector that records its alarm (its estimator provides the
    capability ``fdi-records``, e.g. ``residual-fdi``) on an actuator that records the true fault
    (``true-actuator-fault``: the league's ``fault-battery``) also gets the league's FDI scores: the
    ``fdi-scores`` evaluation and :data:`FDI_METRICS` (the league owns the scores; a method file gives
    none)."""
    from formation_ftc.methods.composed import ComposedScenario, make_loop

    loop = make_loop(cast(ComposedScenario, api.load_scenario(raw, build=False)))

    def add(evaluation: str | None, metrics: tuple[dict[str, Any], ...]) -> None:
        if evaluation is not None:
            raw["evaluations"] = [*raw.get("evaluations", []), {"type": evaluation}]
        raw["metrics"] = [*raw.get("metrics", []), *(dict(m) for m in metrics)]

    estimator = loop.estimator.provides()
    if "navigation-records" in estimator and "lvlh-relative-state" in loop.plant.provides():
        add("navigation-consistency", NAVIGATION_METRICS)
    if not ("fdi-records" in estimator and "true-actuator-fault" in loop.actuator.provides()):
        return raw
    add("fdi-scores", FDI_METRICS)
    if "fault-identification" in estimator:
        add("identification-scores", IDENTIFICATION_METRICS)
    recorded = {sig.name for sig in loop.signals()}
    if "time_in_flfr" in recorded:
        add(None, FLFR_METRICS)
    if "flfr_spacecraft" in recorded:
        add(None, (FLFR_SPACECRAFT_METRIC,))
    return raw


def _network_kind(spec: LeagueSpec, m: MethodEntry) -> tuple[bool, bool]:
    """(has a network, the network has delays) of a method's own file."""
    net = tomllib.loads((spec.source.parent / m.scenario).read_text()).get("network")
    return net is not None, net is not None and net.get("delays") is not None


def _campaign(
    spec: LeagueSpec,
    method: str,
    cell_files: list[Path],
    seeds: int,
    traced: list[int],
    first_seed: int = 0,
) -> dict:
    ie = spec.league.initial_error
    sample: dict[str, Any] = {}
    if ie.seed_field is not None:
        if not ie.seed_field.startswith("plant."):
            raise LeagueError(
                f"league.initial_error.seed_field = {ie.seed_field!r}: must name a plant field"
            )
        sample[ie.seed_field] = {"dist": "integer", "low": 0, "high": 2**31 - 1}
    else:
        truth_field = str(ie.field)
        if not truth_field.startswith("plant."):
            raise LeagueError(
                f"league.initial_error.field = {truth_field!r}: must name a plant field (plant.*)"
            )
        nominal = spec.truth.get(truth_field.removeprefix("plant."))
        if not isinstance(nominal, list) or not all(isinstance(r, list) for r in nominal):
            raise LeagueError(
                f"league.initial_error.field = {truth_field!r}: [truth] has no list of "
                "per-spacecraft vectors there"
            )
        if ie.std and ie.std > 0:
            for i, row in enumerate(nominal):
                for k, v in enumerate(row):
                    normal = {"dist": "normal", "mean": float(v), "std": ie.std}
                    sample[f"{truth_field}.{i}.{k}"] = normal
    overrides: dict[str, Any] = {}
    on = spec.league.onset
    # the actuator fault's onset, and the communication fault's where the method has a network
    networked = _network_kind(spec, spec.method(method))[0]
    for path in (on.field, "network.onset") if networked else (on.field,):
        if on.high > on.low:
            sample[path] = {"dist": "uniform", "low": on.low, "high": on.high}
        else:
            overrides[path] = on.low
    return {
        "campaign": {
            "name": f"league-{spec.league.name}-{method}",
            "base": [str(p) for p in cell_files],
            # a chunk never spans two cells: no larger than the seeds (no padded runs)
            "runs": seeds,
            "first_replicate": first_seed,
            "seed": spec.league.seed,
            "chunk_size": min(spec.league.chunk_size, seeds),
            "paired": True,
            "description": f"league {spec.league.name}: {method}",
        },
        "overrides": overrides,
        "sample": sample,
        "traces": {"runs": traced, "every": 1},
    }


def _provenance() -> dict[str, Any]:
    from formation_ftc.provenance import provenance

    try:
        return dict(provenance())
    except Exception:  # noqa: BLE001 - provenance is best effort, never a reason to fail a league
        return {}


# ------------------------------------------------------------------------------------------ budgets
def check_league_budgets(
    spec: LeagueSpec, cells: dict[str, list[Cell]], seeds: int, budgets: Budgets
) -> None:
    """Refuse, before anything is compiled or written, a league over the budgets campaigns have: the
    integration steps of every cell's run, at most :data:`~formation_ftc.campaign.spec.MAX_RUNS` seeds per
    cell (a campaign's runs per grid point) and the run-steps of every method's campaign (seeds x its
    cells' steps) and of their sum, within ``budgets.max_campaign_steps``. The message names ``--seeds``
    and the range it allows."""
    from formation_ftc.campaign.spec import MAX_RUNS

    name = spec.league.name
    for method, mcells in cells.items():
        for c in mcells:
            check_run_steps(c.n_steps, budgets, f"league {name}, method {method}, cell {c.key}")
    steps_per_seed = {m: sum(c.n_steps for c in mc) for m, mc in cells.items()}
    total_per_seed = sum(steps_per_seed.values())  # the sum bounds every method's campaign too
    allowed, limit = MAX_RUNS, f"the {MAX_RUNS:,} runs per cell a campaign allows"
    budget = budgets.max_campaign_steps
    if budget is not None and total_per_seed and budget // total_per_seed < allowed:
        allowed = budget // total_per_seed
        limit = (
            f"the budget of {budget:,} run-steps (raise it with --max-campaign-steps / "
            "FORMATION_FTC_MAX_CAMPAIGN_STEPS)"
        )
    if seeds <= allowed:
        return
    n_cells = sum(len(mc) for mc in cells.values())
    big = max(cells, key=lambda m: steps_per_seed[m])

    def size(k: int) -> str:
        return (
            f"{k * n_cells:,} runs ({n_cells} cells of {len(cells)} method(s); method {big}: "
            f"{k * len(cells[big]):,} runs) and {k * total_per_seed:,} run-steps"
        )

    if allowed < 1:
        raise LeagueError(
            f"league {name}: even 1 seed per cell makes {size(1)}, over {limit}; shorten "
            "league.horizon or run fewer methods (--methods)"
        )
    raise LeagueError(
        f"--seeds {seeds:,}: league {name} would run {size(seeds)}, over {limit}; allowed: --seeds 1 "
        f"to {allowed:,} for these methods"
    )


def _check_batch_memory(
    spec: LeagueSpec, cells: dict[str, list[Cell]], seeds: int, budgets: Budgets
) -> None:
    """Refuse a method whose batch of ``min(chunk_size, seeds)`` runs needs more memory than the budget
    (first cell of each method, shapes only: every cell of a method has the same structure)."""
    if budgets.max_memory is None:
        return
    batch = min(spec.league.chunk_size, seeds)
    for method, mcells in cells.items():
        if not mcells:
            continue
        where = f"league {spec.league.name}: method {method} cannot be compiled"
        need = run_bytes(mcells[0].raw, LeagueError, where) * batch
        if need > budgets.max_memory:
            raise LeagueError(
                f"league {spec.league.name}, method {method}: a batch of {batch} runs needs about "
                f"{format_bytes(need)} of memory, over the budget of "
                f"{format_bytes(budgets.max_memory)}; lower league.chunk_size in the league file, "
                "or raise the budget with --max-memory / FORMATION_FTC_MAX_MEMORY"
            )


def run_bytes(raw: dict[str, Any], error: type[InputError], where: str) -> int:
    """Estimated memory of one run of the full scenario ``raw`` [bytes] (shapes only); a run that
    cannot be built raises ``error`` (``where: reason``)."""
    try:
        return run_memory_bytes(api.build_loop(api.load_scenario(dict(raw))))
    except InputError:
        raise
    except (ValueError, TypeError, ArithmeticError, RecursionError) as exc:
        raise error(f"{where}: {exc}") from None


# ------------------------------------------------------------------------------ league directory
class _Record(BaseModel):
    """A part of ``league.json``: the types every reader relies on (strict: ``"3"`` is no integer);
    fields it does not know are kept (a newer writer)."""

    model_config = ConfigDict(strict=True, extra="allow")


class _CaseRecord(_Record):
    name: str
    kind: str


class _BatteryRecord(_Record):
    name: str
    version: str | int
    sha256: str = ""
    cases: list[_CaseRecord]


class _NamedRecord(_Record):
    name: str

    @field_validator("name")
    @classmethod
    def _one_component(cls, v: str) -> str:
        # a method's name is a directory of the league: one path component
        if v in ("", ".", "..") or "/" in v or "\\" in v:
            raise ValueError(f"{v!r} is not a name (one path component)")
        return v


class StepCheckRecord(_Record):
    """A method's step check as ``league.json`` records it (:class:`~formation_ftc.league.step_check.StepCheckResult`)."""

    chosen_dt: float = Field(gt=0, allow_inf_nan=False)
    converged: bool = True


class LeagueRecord(_Record):
    """``league.json`` of a league directory, as :func:`run_league` writes it."""

    name: str
    version: str
    kind: str = "translational"
    hash: str
    seeds: int = Field(ge=1)
    quick: bool = False
    definition: str
    method_files: dict[str, str] = {}
    battery: _BatteryRecord
    methods: list[_NamedRecord]
    levels: list[_NamedRecord]
    step_check: dict[str, StepCheckRecord] = {}
    provenance: dict[str, Any] = {}
    #: a league run in blocks of seeds: [first seed, seeds] of each (``seeds`` is their sum)
    blocks: list[list[int]] = []

    @field_validator("blocks")
    @classmethod
    def _contiguous(cls, v: list[list[int]]) -> list[list[int]]:
        if any(len(b) != 2 for b in v):
            raise ValueError(f"{v!r}: each block is [first seed, seeds]")
        ends = [0] + [a + n for a, n in v]
        if any(a != e or n < 1 for (a, n), e in zip(v, ends, strict=False)):
            raise ValueError(f"{v!r}: blocks of seeds must follow each other from seed 0")
        return v


def record_error(path: Path | str, exc: ValidationError, prefix: str = "") -> str:
    """``FILE: field a.b.c: what is wrong (got ...)`` of the first error of ``exc`` (and how many
    more); ``prefix``: the field that was validated (its path in the file)."""
    first, *others = exc.errors()
    where = ".".join(map(str, ([prefix] if prefix else []) + [*first["loc"]])) or "(top level)"
    got = "" if first["type"] == "missing" else f" (got {first.get('input')!r:.60})"
    more = f"; {len(others)} more problem(s)" if others else ""
    return f"{path}: field {where}: {first['msg']}{got}{more}"


def _check_definition(meta: dict[str, Any]) -> str | None:
    """What is wrong with the league definition text of ``league.json`` (None: readable)."""
    try:
        league = tomllib.loads(meta["definition"])["league"]
        req = league["requirement"]
        ok = isinstance(req["metric"], str) and isinstance(req.get("units", ""), str)
        for v in (req["max"], league["horizon"]):
            ok = ok and isinstance(v, int | float) and not isinstance(v, bool)
    except (ValueError, KeyError, TypeError) as exc:
        return f"not a league definition ({type(exc).__name__}: {exc})"
    return None if ok else "league.requirement or league.horizon of the wrong type"


def _read_meta(
    path: Path, what: str, advice: str = "restore the file, or give another --out (new or empty)"
) -> dict[str, Any]:
    """``league.json`` as a dict, its types checked (:class:`LeagueRecord`); LeagueError naming
    ``what`` (e.g. ``--out DIR``), the file and the field when it is damaged or mistyped."""
    try:
        meta = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:  # JSONDecodeError, UnicodeDecodeError are ValueErrors
        reason = getattr(exc, "strerror", None) or exc
        raise LeagueError(
            f"{what}: {LEAGUE_FILE} is damaged or unreadable ({reason}); refusing to use the "
            f"directory: {advice}"
        ) from None
    if not isinstance(meta, dict) or not {"hash", "seeds", "methods", "battery"} <= set(meta):
        raise LeagueError(
            f"{what}: {LEAGUE_FILE} is not a league description (damaged, or another program's "
            f"file); refusing to use the directory: {advice}"
        )
    try:
        LeagueRecord.model_validate(meta)
    except ValidationError as exc:
        raise LeagueError(f"{what}: {record_error(path, exc)}; {advice}") from None
    problem = _check_definition(meta)
    if problem:
        raise LeagueError(f"{what}: {path}: field definition: {problem}; {advice}")
    return meta


def _campaign_at_or_above(path: Path) -> Path | None:
    """The nearest campaign directory holding ``path`` (or ``path`` itself): one with a campaign
    manifest, the marker the campaign store writes first."""
    from formation_ftc.campaign.storage import FORMAT, MANIFEST

    real = Path(os.path.realpath(path))
    for d in (real, *real.parents):
        marker = d / MANIFEST
        with contextlib.suppress(OSError, ValueError, AttributeError):  # unreadable: not a campaign
            if marker.is_file() and json.loads(marker.read_text("utf-8")).get("format") == FORMAT:
                return d
    return None


def _check_target(
    out: Path, what: str, error: type[InputError], in_campaign: str, not_dir: str
) -> bool:
    """Refuse (``error``) an ``--out`` that is a campaign directory or lies inside one (``in_campaign``:
    the advice), or exists and is not a directory (``not_dir``); whether it exists. An unusable path
    raises OSError."""
    campaign = _campaign_at_or_above(out)
    if campaign is not None:
        inside = campaign != Path(os.path.realpath(out))
        where = f"is inside {campaign}, which is" if inside else "is"
        raise error(f"{what}: {where} a campaign directory; {in_campaign}")
    return existing_dir(out, what, error, not_dir)


def _check_out(
    out: Path, spec: LeagueSpec, digest: str, seeds: int, first_seed: int | None = None
) -> dict[str, Any] | None:
    """Refuse, before anything is written, an ``--out`` this league may not use: a file or a device, a
    path inside (or equal to) a campaign directory, a directory that is neither empty nor this league
    (same definition and seeds: resumed). A block of seeds (``first_seed`` not None) extends a league
    run in blocks when it starts where the league's seeds end or is one of its blocks (resumed).
    Returns the ``league.json`` found there, or None."""
    what = f"--out {out}"
    with oserror_as(LeagueError, f"{what}: unusable path"):
        if not _check_target(
            out,
            what,
            LeagueError,
            "a league writes one campaign per method in its own directory: give another --out "
            "(new or empty)",
            "give a directory (new or empty, or this league's to resume it)",
        ):
            return None
        entries = [e.name for e in out.iterdir()]
        if LEAGUE_FILE not in entries:
            stray = sorted(e for e in entries if not TMP_RE.match(e))
            if stray:
                raise LeagueError(
                    f"{what}: is not empty and holds no {LEAGUE_FILE} (e.g. {stray[:3]}): not a "
                    "league directory; refusing to write there. Give a new or empty directory"
                )
            if first_seed:  # None or 0: a new league
                raise LeagueError(
                    f"{what}: holds no league; a block of seeds from {first_seed} extends a league "
                    "directory that holds the seeds before it"
                )
            return None
    old = _read_meta(out / LEAGUE_FILE, what)
    blocks = old.get("blocks") or []
    if first_seed is None:
        fits = not blocks and old.get("seeds") == seeds
    else:
        fits = bool(blocks) and (old.get("seeds") == first_seed or [first_seed, seeds] in blocks)
    if blocks and first_seed is None and old.get("hash") == digest:
        raise LeagueError(
            f"{out}: holds league {old.get('name')!r} run in blocks of seeds "
            f"({old.get('seeds')} seeds so far): resume it with `league run --until-resolved`, or "
            f"write its leaderboard with `league report {out}`"
        )
    if old.get("hash") != digest or not fits:
        raise LeagueError(
            f"{out}: holds league {old.get('name')!r} (definition {str(old.get('hash'))[:12]}, "
            f"{old.get('seeds')} seeds); this is {spec.league.name!r} ({digest[:12]}, {seeds} "
            "seeds). Use another --out directory"
        )
    return old


def _write_inputs(
    out: Path, meta: dict[str, Any], cells: dict[str, list[Cell]]
) -> dict[str, list[Path]]:
    """``league.json`` and every method's cell files (only those whose content changed); the cell files."""
    import tomli_w

    try:
        out.mkdir(parents=True, exist_ok=True)
        atomic_write(out / LEAGUE_FILE, json.dumps(meta, indent=1, default=str))
        files: dict[str, list[Path]] = {}
        for name, mcells in cells.items():
            cdir = out / name / "cells"
            cdir.mkdir(parents=True, exist_ok=True)
            files[name] = []
            for c in mcells:
                p = cdir / f"{c.key}.toml"
                text = tomli_w.dumps(c.raw)  # tomli_w writes tuples as arrays and inf as ``inf``
                if not p.is_file() or p.read_text(encoding="utf-8") != text:
                    atomic_write(p, text)
                files[name].append(p)
        return files
    except OSError as exc:
        if exc.errno in DISK_FULL:  # a full disk: exit status 3, one line
            raise OSError(exc.errno, exc.strerror, str(out)) from None
        raise LeagueError(
            f"--out {out}: cannot write the league there ({exc.strerror or exc}); give a writable "
            "directory"
        ) from None


# ------------------------------------------------------------------------------------------- progress
def _stored_runs(chunks: Path, seeds: int, chunk_size: int) -> int:
    """Runs in the chunk files a method's campaign has stored (a chunk file exists once it is finished;
    a cell's ``seeds`` runs are ``ceil(seeds / chunk_size)`` chunks, the last one shorter)."""
    per_cell = -(-seeds // chunk_size)
    try:
        names = os.listdir(chunks)
    except OSError:
        return 0
    ids = [int(m[1]) for m in map(_CHUNK_RE.match, names) if m]
    return sum(min(chunk_size, seeds - (i % per_cell) * chunk_size) for i in ids)


#: a league line's clocks: elapsed (stopped when the line is done) and ETA
_CLOCKS = (
    lambda t: f"[progress.elapsed]{_clock(t.finished_time if t.finished else t.elapsed)}",
    "ETA",
    lambda t: f"[progress.remaining]{_clock(t.time_remaining)}",
)


class _MethodProgress(_Bars):
    """One progress line per method (runs done, elapsed, ETA) on a terminal's stderr, read from the
    chunk files each method's campaign has stored: it follows methods computed side by side in other
    processes."""

    def __init__(
        self, methods: list[tuple[str, Path, int]], seeds: int, chunk_size: int, **options: Any
    ):
        tasks = {name: {"total": total} for name, _, total in methods}
        super().__init__(tasks, "runs", *_CLOCKS, terminal_only=True, **options)
        self.methods, self.seeds, self.chunk_size = methods, seeds, chunk_size

    def _poll(self) -> None:
        for name, chunks, total in self.methods:
            done = min(total, _stored_runs(chunks, self.seeds, self.chunk_size))
            self.update_line(name, completed=done)


class Counter(_Bars):
    """One progress line counting ``unit`` of a phase (the step checks' integration steps, a tuning's
    evaluations) on a terminal's stderr: :meth:`advance` as they finish, :meth:`expect` when more turn
    out to be needed. Without a terminal (or disabled) it counts and draws nothing."""

    def __init__(self, label: str, total: int, unit: str, **options: Any):
        super().__init__({label: {"total": total}}, unit, *_CLOCKS, terminal_only=True, **options)
        self.label, self.total, self.done = label, total, 0

    def advance(self, n: int = 1) -> None:
        self.done += n

    def expect(self, n: int) -> None:
        """``n`` more than the total planned so far."""
        self.total += n

    def _poll(self) -> None:
        total = max(self.total, self.done)  # an optimiser may pass its budget
        self.update_line(self.label, completed=self.done, total=total)


# ----------------------------------------------------------------------------------------------- run
def _run_method_campaign(
    campaign: dict, out_dir: str, executor_factory: Callable
) -> tuple[int, int, float]:
    """One method's campaign with the executor ``executor_factory()`` makes (in this process, or in a
    worker of :func:`run_league`): (runs, failed, seconds)."""
    from formation_ftc.campaign.runner import run_campaign

    t0 = time.perf_counter()
    outcome = run_campaign(campaign, out_dir, executor=executor_factory())
    return outcome.n_runs, outcome.n_failed, time.perf_counter() - t0


def run_league(
    league: str | Path | LeagueSpec,
    out_dir: str | Path,
    *,
    seeds: int | None = None,
    quick: bool = False,
    methods: list[str] | None = None,
    executor_factory: Callable | None = None,
    progress: bool = False,
    log: Callable[[str], None] | None = None,
    parallel_methods: int = 1,
    budgets: Budgets | None = None,
    first_seed: int | None = None,
) -> LeagueOutcome:
    """Run (or resume) ``league`` into ``out_dir``: ``DIR/league.json`` (definition, battery, seeds,
    provenance) and one campaign directory per method (``DIR/<method>/campaign``).

    ``first_seed`` (None: a league of ``seeds`` seeds) runs the block of seeds ``first_seed ..
    first_seed + seeds - 1`` (replicates of the same streams: the runs a league of more seeds has) and
    adds it to the league in ``out_dir``: the first block in ``DIR/<method>/campaign``, a later one in
    ``DIR/<method>/campaign-from-<first_seed>``; ``league.json`` lists the blocks and counts their seeds
    (:func:`formation_ftc.league.resolution.run_until_resolved`).

    ``parallel_methods`` > 1: that many methods run side by side, one process each (each method's chunks
    in that process; the processes exit when this one dies); otherwise the methods run one after the
    other, each campaign with the executor from ``executor_factory`` (local processes by default, or
    Dask). ``budgets`` (default: :meth:`Budgets.resolve`, the environment's or the defaults) bound the
    league before anything is written. ``progress``: on a terminal's stderr, a line for the step checks,
    then one line per method.
    ``log`` gets one line per finished method; an OSError or ValueError it raises (a closed or full
    stderr) is ignored."""
    from formation_ftc.campaign.executors import LocalExecutor, die_with_parent

    t0 = time.perf_counter()
    spec = league if isinstance(league, LeagueSpec) else load_league(league)
    default_seeds = spec.league.quick_seeds if quick else spec.league.seeds
    n_seeds = int(seeds if seeds is not None else default_seeds)
    if n_seeds < 1:
        raise LeagueError(f"--seeds = {n_seeds}: at least 1 seed per cell")
    cells = plan_cells(spec, methods)  # everything validated before anything is written
    for name, mcells in cells.items():
        sampled = _campaign(spec, name, [], 1, [])
        for path in [*sampled["sample"], *sampled["overrides"]]:
            for c in mcells:
                if not _has_path(c.raw, path):
                    raise LeagueError(
                        f"league {spec.league.name}: the league samples {path!r}, but method {name}'s "
                        f"cell {c.key} has no such field (give it a value in [truth], [actuator] or "
                        "the method's network)"
                    )
    budgets = budgets if budgets is not None else Budgets.resolve()
    check_league_budgets(spec, cells, n_seeds, budgets)
    out = Path(out_dir)
    digest = league_hash(spec)
    old = _check_out(out, spec, digest, n_seeds, first_seed)
    start = first_seed or 0
    step_checks = _step_checks(spec, cells, old, log, progress)
    if step_checks:  # a finer chosen step: the budgets again, on the steps that will run
        check_league_budgets(spec, cells, n_seeds, budgets)
    _check_batch_memory(spec, cells, n_seeds, budgets)
    battery = _battery(spec)
    # ``old`` is a validated LeagueRecord: every method entry has a name
    listed = set(cells) | {m["name"] for m in (old or {}).get("methods", [])}
    meta = {
        "name": spec.league.name,
        "version": spec.league.version,
        "kind": spec.league.kind,
        "hash": digest,
        "seeds": n_seeds,
        "quick": quick,
        **_blocks(old, start, n_seeds, first_seed is not None),
        "definition_file": spec.source.name,
        "definition": spec.source.read_text(),
        "method_files": {
            m.name: (spec.source.parent / m.scenario).read_text() for m in spec.methods
        },
        "battery": {
            "name": battery.name,
            "version": battery.version,
            "sha256": battery.sha256,
            "cases": [{"name": c.name, "kind": c.kind} for c in battery.cases],
        },
        # the methods of earlier runs into this directory stay listed (a resume with another --methods)
        "methods": [m.model_dump() for m in spec.methods if m.name in listed],
        "levels": [lv.model_dump() for lv in spec.levels],
        "step_check": {**(old or {}).get("step_check", {}), **step_checks},
        "provenance": _provenance(),
    }
    files = _write_inputs(out, meta, cells)
    trace_seed = spec.league.trace_seed - start  # the trace seed's block keeps its traces
    folder = campaign_folder(start)
    jobs = {}  # method -> (its campaign, its campaign directory)
    for name, mcells in cells.items():
        traced = _traced_runs(mcells, n_seeds, trace_seed, spec.league.trace_cases)
        campaign = _campaign(spec, name, files[name], n_seeds, traced, start)
        jobs[name] = (campaign, str(out / name / folder))
    finished: dict[str, tuple[int, int, float]] = {}  # method -> (runs, failed, seconds)

    def done(name: str, result: tuple[int, int, float]) -> None:
        finished[name] = runs, failed, seconds = result
        _say(log, f"{name}: {runs} runs, {failed} failed, {seconds:.1f} s")

    watched = [
        (name, Path(d, "chunks"), n_seeds * len(cells[name])) for name, (_, d) in jobs.items()
    ]
    with _MethodProgress(watched, n_seeds, min(spec.league.chunk_size, n_seeds), enabled=progress):
        if parallel_methods > 1 and len(jobs) > 1:
            # one process per method (each compiles its program once and runs its chunks in-process):
            # the methods' campaigns are independent directories, so they run side by side
            import concurrent.futures
            import multiprocessing

            with concurrent.futures.ProcessPoolExecutor(
                max_workers=min(parallel_methods, len(jobs)),
                mp_context=multiprocessing.get_context("spawn"),
                initializer=die_with_parent,
                initargs=(os.getpid(),),
            ) as pool:
                in_worker = functools.partial(LocalExecutor, workers=1)
                futures = {
                    pool.submit(_run_method_campaign, *job, in_worker): name
                    for name, job in jobs.items()
                }
                try:
                    for fut in concurrent.futures.as_completed(futures):
                        done(futures[fut], fut.result())
                finally:
                    for fut in futures:
                        fut.cancel()  # methods not started yet; the running ones finish their chunk
        else:  # without a factory: each campaign's automatic local pool
            for name, job in jobs.items():
                done(name, _run_method_campaign(*job, executor_factory or LocalExecutor))
    runs, failed = sum(r[0] for r in finished.values()), sum(r[1] for r in finished.values())
    per_method = {name: r[2] for name, r in finished.items()}  # in the order they finished
    return LeagueOutcome(out, runs, failed, time.perf_counter() - t0, per_method)


def campaign_folder(first_seed: int) -> str:
    """A method's campaign directory (under ``DIR/<method>/``) of the block of seeds from
    ``first_seed``: ``campaign`` for the first, ``campaign-from-000020`` for one from seed 20."""
    return "campaign" if not first_seed else f"campaign-from-{first_seed:06d}"


def _blocks(old: dict[str, Any] | None, start: int, seeds: int, blocked: bool) -> dict[str, Any]:
    """``league.json``'s ``seeds`` and ``blocks`` ([first seed, seeds] of each block) after a block of
    ``seeds`` from ``start`` (``blocked``), or ``{}`` for a league run in one piece."""
    if not blocked:
        return {}
    blocks = [b for b in (old or {}).get("blocks", []) if b != [start, seeds]] + [[start, seeds]]
    blocks.sort()
    return {"seeds": sum(n for _, n in blocks), "blocks": blocks}


def _say(log: Callable[[str], None] | None, line: str) -> None:
    """``log(line)`` when there is a log; a closed or full stderr must not cost a computed result."""
    if log is not None:
        with contextlib.suppress(OSError, ValueError):
            log(line)


def _step_checks(
    spec: LeagueSpec,
    cells: dict[str, list[Cell]],
    old: dict[str, Any] | None,
    log: Callable[[str], None] | None,
    progress: bool = False,
) -> dict[str, dict[str, Any]]:
    """Run (or, on a resume, reuse) each method's step-convergence check
    (:mod:`formation_ftc.league.step_check`) and give every cell of the method the chosen step.
    Returns the checks' records for ``league.json`` ({} when the league disables the check).
    ``progress``: a progress line (integration steps simulated, elapsed, ETA) on a terminal's
    stderr from the first second; its total grows when a method's step has to be halved again."""
    from formation_ftc.league.step_check import check_step

    sc = spec.league.step_check
    if not sc.enabled:
        return {}
    level = sc.level if sc.level is not None else spec.levels[0].name
    if level not in {lv.name for lv in spec.levels}:
        raise LeagueError(f"league.step_check.level = {level!r}: not a level of this league")
    done = (old or {}).get("step_check", {})
    checks: dict[str, Cell] = {}
    for name, mcells in cells.items():
        if done.get(name) is not None:
            continue
        cell = next((c for c in mcells if (c.case, c.level) == (sc.case, level)), None)
        if cell is None:
            raise LeagueError(
                f"league.step_check.case = {sc.case!r}: method {name} has no cell "
                f"{sc.case}/{level} (give a fault case of the battery that applies to it)"
            )
        checks[name] = cell
    if checks:
        _say(
            log,
            f"step checks: {len(checks)} method(s) ({', '.join(checks)}), each at its step and "
            "half of it (halved again while the scores move by more than "
            f"{sc.tolerance * 100:g} %)",
        )
    # the check flies its cell at dt and dt/2 (3 x the cell's steps), more when it halves again
    planned = sum(3 * c.n_steps for c in checks.values())
    out: dict[str, dict[str, Any]] = {}
    with Counter("step checks", planned, "steps", enabled=progress) as bar:
        for name, mcells in cells.items():
            record = done.get(name)
            if record is None:
                cell = checks[name]
                horizon, dt0 = (float(cell.raw["simulation"][k]) for k in ("horizon", "dt"))

                def on_simulation(dt: float, finished: bool, dt0: float = dt0, h: float = horizon):
                    steps = int(round(h / dt))
                    if finished:
                        bar.advance(steps)
                    elif dt < dt0 / 3:  # finer than dt/2: not in the plan
                        bar.expect(steps)

                record = check_step(
                    name,
                    cell.raw,
                    case=sc.case,
                    level=level,
                    onset_field=spec.league.onset.field,
                    onset=spec.league.onset.low,
                    tolerance=sc.tolerance,
                    max_halvings=sc.max_halvings,
                    ignore=_NOT_STEP_CHECKED,
                    on_simulation=on_simulation,
                ).as_dict()
                verdict = "converged" if record["converged"] else "NOT converged, kept"
                changes = ", ".join(f"{c:.2%}" for c in record["changes"])
                _say(
                    log,
                    f"{name}: step check {verdict} at dt = {record['chosen_dt']:g} s "
                    f"(largest score change per halving: {changes})",
                )
            out[name] = record
            dt = float(record["chosen_dt"])
            for j, c in enumerate(mcells):
                c.raw["simulation"]["dt"] = dt
                n_steps = int(round(float(c.raw["simulation"]["horizon"]) / dt))
                mcells[j] = dataclasses.replace(c, n_steps=n_steps)
    return out


def _has_path(raw: dict, path: str) -> bool:
    node: Any = raw
    for part in path.split("."):
        if isinstance(node, dict) and part in node:
            node = node[part]
        elif isinstance(node, list) and part.isdigit() and int(part) < len(node):
            node = node[int(part)]
        else:
            return False
    return True


def _traced_runs(cells: list[Cell], seeds: int, trace_seed: int, cases: list[str]) -> list[int]:
    """Run ids whose time histories are kept: the trace seed of the trace cases at the first level
    (each kept history is one more run, re-run alone with its records); none when the trace seed
    is not one of the ``seeds`` (another block of seeds keeps them)."""
    first_level = cells[0].level if cells else ""
    traced = [g for g, c in enumerate(cells) if c.level == first_level and c.case in cases]
    return [g * seeds + trace_seed for g in traced] if 0 <= trace_seed < seeds else []


def load_league_results(out_dir: str | Path) -> tuple[dict[str, Any], pd.DataFrame]:
    """``(league.json, one row per run)`` with columns method, case, fault_kind, level, replicate, seed,
    status, diagnostic and ``metric:*``."""
    from formation_ftc.campaign.storage import CampaignStore

    out = Path(out_dir)
    meta_path = out / LEAGUE_FILE
    if not meta_path.is_file():
        raise LeagueError(
            f"{out}: no {LEAGUE_FILE}; run `formation-ftc league run NAME --out {out}` first"
        )
    meta = _read_meta(
        meta_path, str(out), f"run `formation-ftc league run NAME --out {out}` into a new directory"
    )
    kinds = {c["name"]: c["kind"] for c in meta["battery"]["cases"]}
    frames = []
    blocks = [campaign_folder(first) for first, _ in meta.get("blocks", [[0, 0]])]
    for m in meta["methods"]:
        mdir = out / m["name"]
        parts = [CampaignStore.read(mdir / b).load_results() for b in blocks if (mdir / b).is_dir()]
        parts = [p for p in parts if len(p)]
        if not parts:
            continue
        df = pd.concat(parts, ignore_index=True) if len(parts) > 1 else parts[0]
        keys = df["scenario"].map(lambda s: Path(str(s)).stem).str.split("--")  # case--level
        df = df.assign(method=m["name"], case=keys.str[0], level=keys.str[1])
        df["fault_kind"] = df["case"].map(kinds)
        frames.append(df)
    if not frames:
        raise LeagueError(f"{out}: no finished runs yet")
    return meta, pd.concat(frames, ignore_index=True)
