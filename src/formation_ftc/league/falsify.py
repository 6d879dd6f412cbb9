"""The worst case found: search the fault (kind, channel, onset, magnitude, duration), the initial
errors and the noise seed of one league method and level for the run with the lowest requirement
robustness (``formation-ftc falsify``).

The search space is the unit cube ``[0, 1]^d`` (:data:`COORDINATES`), mapped to a fault of the
league's actuator (``fault-battery``) on the method's league cell of that fault kind:

* ``kind``: one of the battery's actuator fault kinds (the cube's coordinate split into equal parts:
  a relaxation of the categorical choice, which CMA-ES searches like the others);
* ``spacecraft``, ``axis``: the faulty channel; ``onset`` in the league's onset range [s];
* ``effectiveness`` in [0, 1] (loss of effectiveness); ``bias`` in [-b, b] with b the level's per-axis
  limit (1 N unsaturated, the battery's bias); ``period`` in [10, 200] s and ``duty`` in [0.1, 0.9]
  (intermittent); ``rate`` in [1e-4, 1e-2] 1/s and ``min_effectiveness`` in [0, 1] (degrading); a
  stuck or outage fault has no magnitude;
* ``initial_error`` and ``noise``: the seeds of the league's initial-error draw and of the run's noise
  (integers in [0, 2^31)).

The robustness of a run is that of the league's STL requirement when it states one (minus its
``stl_violation``), else ``max - metric`` of its metric requirement; a run that diverges has robustness
-inf. A candidate population is one ``jax.vmap`` batch per fault kind (a kind is a structure: one
compiled program each, padded to the population size), so the search compiles a handful of programs,
not one per run. The optimiser is CMA-ES (``cma``, bounded to the cube) or uniform random sampling
(the baseline of the ARCH-COMP falsification competition); both stop at the first violation
(robustness < 0) or at the run budget, and report the runs to it. ``kinds`` restricts the search to
some fault kinds (one kind: a search per kind, without the relaxed categorical coordinate).

The smallest magnitude that breaks the law (:func:`min_magnitudes`): per fault kind, at the kind's
lowest-robustness run of the search (its channel, onset and seeds; a seeded random one for a kind the
search did not draw), the fault's severity ``s`` in [0, 1] (:data:`SEVERITY`: the lost effectiveness
``1 - effectiveness``, the bias as a fraction of the level's limit with the sign found, the off-fraction
``1 - duty`` of an intermittent fault, the depth ``1 - min_effectiveness`` of a degrading one) is
bracketed by a section search: a population of severities evenly spaced over the bracket, one vmapped
batch each round, the bracket narrowed to the interval where the robustness first turns negative. It
assumes the robustness falls as the severity grows, and says so where the samples contradict it.
"""

from __future__ import annotations

import copy
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from formation_ftc.components.actuators.fault_battery import FAULT_KINDS
from formation_ftc.league.definition import STL_VIOLATION, LeagueError, LeagueSpec, load_league

__all__ = [
    "COORDINATES",
    "FALSIFIABLE_KINDS",
    "SEVERITY",
    "candidate_raw",
    "falsify",
    "FalsifyResult",
    "min_magnitudes",
]

#: the cube's coordinates, in order
COORDINATES = (
    "kind",
    "spacecraft",
    "axis",
    "onset",
    "effectiveness",
    "bias",
    "period",
    "duty",
    "rate",
    "min_effectiveness",
    "initial_error",
    "noise",
)
#: actuator fault kinds the search draws: every kind of the fault-battery actuator but "none"
FALSIFIABLE_KINDS = FAULT_KINDS[1:]
SEEDS = 2**31
#: the severity s in [0, 1] of a fault kind with a magnitude: (what s is, the actuator field it sets)
SEVERITY = {
    "loss_of_effectiveness": ("lost effectiveness 1 - effectiveness", "effectiveness"),
    "bias": ("bias as a fraction of the level's per-axis limit (1 N unsaturated)", "bias"),
    "intermittent": ("off-fraction 1 - duty of each period", "duty"),
    "degrading": ("depth 1 - min_effectiveness", "min_effectiveness"),
}


def _pick(u: float, n: int) -> int:
    return min(int(u * n), n - 1)


def _mix(lo: float, hi: float, u: float, log: bool = False) -> float:
    if log:
        return float(math.exp(math.log(lo) + u * (math.log(hi) - math.log(lo))))
    return float(lo + u * (hi - lo))


def _bias_limit(actuator: dict[str, Any]) -> float:
    """The largest bias searched: the level's per-axis limit, or the battery's 1 N unsaturated."""
    limit = actuator.get("saturation")
    return float(limit) if limit is not None else 1.0


def _with_severity(raw: dict[str, Any], fault: dict[str, Any], s: float) -> dict[str, Any]:
    """``raw`` (a candidate of kind ``fault["kind"]``) with the fault's severity set to ``s``."""
    raw = copy.deepcopy(raw)
    act, kind = raw["actuator"], fault["kind"]
    if kind == "bias":
        act["bias"] = math.copysign(s * _bias_limit(act), fault.get("bias", 1.0) or 1.0)
    else:
        act[SEVERITY[kind][1]] = 1.0 - s
    return raw


def _raw_of(spec: LeagueSpec, cells: dict[str, Any], fault: dict[str, Any]) -> dict[str, Any]:
    """The scenario of a drawn ``fault`` (kind, channel, onset, magnitudes, seeds) on its kind's cell."""
    if spec.league.onset.field != "actuator.onset":
        raise LeagueError(
            f"league.onset.field = {spec.league.onset.field!r}: falsify needs actuator.onset"
        )
    raw = copy.deepcopy(cells[fault["kind"]].raw)
    raw["actuator"].update(
        {k: v for k, v in fault.items() if k not in ("kind", "initial_error_seed", "noise_seed")}
    )
    field = str(spec.league.initial_error.seed_field).removeprefix("plant.")
    raw["plant"][field] = fault["initial_error_seed"]
    raw["simulation"]["seed"] = fault["noise_seed"]
    return raw


def candidate_raw(
    spec: LeagueSpec, cells: dict[str, Any], level: str, u: np.ndarray
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The full scenario of the point ``u`` of the unit cube (:data:`COORDINATES`) on the method's
    cells ``cells`` (kind -> its league cell at ``level``), and the fault it draws (JSON-able)."""
    u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
    x = dict(zip(COORDINATES, u, strict=True))
    kinds = [k for k in FALSIFIABLE_KINDS if k in cells]
    kind = kinds[_pick(x["kind"], len(kinds))]
    act = cells[kind].raw["actuator"]
    n = len(spec.truth.get("mass", [])) or len(spec.truth.get("initial_attitude_deg", [])) or 4
    on = spec.league.onset
    fault: dict[str, Any] = {
        "kind": kind,
        "spacecraft": _pick(x["spacecraft"], n) + 1,
        "axis": _pick(x["axis"], 3),
        "onset": _mix(on.low, on.high, x["onset"]),
    }
    bias = _bias_limit(act)
    ranges = {  # each kind's magnitudes: field -> (low, high); the rate is drawn on a log scale
        "loss_of_effectiveness": {"effectiveness": (0.0, 1.0)},
        "bias": {"bias": (-bias, bias)},
        "intermittent": {"period": (10.0, 200.0), "duty": (0.1, 0.9)},
        "degrading": {"rate": (1e-4, 1e-2), "min_effectiveness": (0.0, 1.0)},
    }
    for field, (low, high) in ranges.get(kind, {}).items():
        fault[field] = _mix(low, high, x[field], log=field == "rate")
    fault["initial_error_seed"] = _pick(x["initial_error"], SEEDS)
    fault["noise_seed"] = _pick(x["noise"], SEEDS)
    return _raw_of(spec, cells, fault), fault


def _robustness(spec: LeagueSpec, metrics: dict[str, float], diverged: bool) -> float:
    """The run's requirement robustness (>= 0: it passes)."""
    if diverged:
        return -math.inf
    if spec.league.requirement.stl is not None:
        return -float(metrics[STL_VIOLATION])
    return float(spec.league.requirement.max) - float(metrics[spec.league.requirement.metric])


def _run_candidates(
    spec, built: list[tuple[dict, dict]], size: int
) -> list[tuple[float, dict, dict]]:
    """(robustness, fault, raw) of every (raw, fault), batched by fault kind (padded to ``size``)."""
    import jax

    from formation_ftc import api
    from formation_ftc.sim.batch import batched_run, stack_params

    out: list[Any] = [None] * len(built)
    groups: dict[str, list[int]] = {}
    for i, (_, fault) in enumerate(built):
        groups.setdefault(fault["kind"], []).append(i)
    for idx in groups.values():
        loops = [api.build_loop(api.load_scenario(built[i][0])) for i in idx]
        batch, axes = stack_params(loops, size)
        res = jax.device_get(batched_run(loops[0], axes, size)(batch))
        for j, i in enumerate(idx):
            one = jax.tree_util.tree_map(lambda a, j=j: a[j], res)
            metrics = loops[0].metric_values(one)
            diverged = int(np.asarray(one["diverged_step"])) >= 0
            out[i] = (_robustness(spec, metrics, diverged), built[i][1], built[i][0])
    return out


@dataclass
class FalsifyResult:
    """What a search found: ``found`` (a violation), ``runs`` (evaluated), ``runs_to_violation``
    (None when none was found), the ``best`` robustness, its ``fault`` and scenario ``raw``, and the
    ``history`` of (runs, best robustness) after every population; ``worst`` the lowest robustness
    per fault kind drawn (robustness, fault); ``magnitudes`` the smallest breaking magnitude per kind
    (:func:`min_magnitudes`) when asked for."""

    method: str
    level: str
    optimizer: str
    seed: int
    budget: int
    found: bool
    runs: int
    runs_to_violation: int | None
    best: float
    fault: dict[str, Any]
    raw: dict[str, Any]
    history: list[tuple[int, float]]
    seconds: float
    worst: dict[str, tuple[float, dict[str, Any]]]
    magnitudes: list[dict[str, Any]] | None = None


def falsify(
    league: str | LeagueSpec,
    method: str,
    level: str,
    *,
    budget: int = 200,
    seed: int = 0,
    optimizer: str = "cma",
    population: int = 8,
    step_checks: dict[str, Any] | None = None,
    kinds: list[str] | None = None,
    min_magnitude: bool = False,
    rounds: int = 3,
) -> FalsifyResult:
    """Search ``method`` at ``level`` of ``league`` for a run that violates the requirement, with at
    most ``budget`` runs (``population`` per batch), by CMA-ES from a random point (step 0.3) or
    uniform random sampling; ``seed`` seeds the optimiser. ``step_checks`` (a league's ``league.json``
    record): fly the method at the step its league check chose (default: run the check). ``kinds``:
    search only these fault kinds. ``min_magnitude``: then bracket each kind's smallest breaking
    severity in ``rounds`` section rounds (:func:`min_magnitudes`; its runs are not in ``runs``)."""
    from formation_ftc.league.runner import _step_checks, plan_cells

    spec = league if isinstance(league, LeagueSpec) else load_league(league)
    if optimizer not in ("cma", "random"):
        raise LeagueError(f"--optimizer {optimizer!r}: 'cma' or 'random'")
    if budget < 1 or population < 2:
        raise LeagueError(f"--budget {budget}, --population {population}: at least 1 and 2")
    if spec.league.initial_error.seed_field is None:
        raise LeagueError(
            f"league {spec.league.name}: falsify searches the initial errors through their seed "
            "(league.initial_error.seed_field); this league samples them per component"
        )
    spec.method(method)  # LeagueError naming the methods
    if level not in [lv.name for lv in spec.levels]:
        raise LeagueError(
            f"--level {level!r}: not a level of league {spec.league.name} "
            f"({', '.join(lv.name for lv in spec.levels)})"
        )
    planned = plan_cells(spec, [method])
    _step_checks(spec, planned, {"step_check": dict(step_checks or {})}, None)
    cells = {c.fault_kind: c for c in planned[method] if c.level == level}
    allowed = [k for k in FALSIFIABLE_KINDS if k in cells]
    if not allowed:
        raise LeagueError(f"method {method} has no actuator-fault cell at level {level}")
    wrong = [k for k in kinds or () if k not in allowed]
    if wrong:
        raise LeagueError(f"--kind {wrong[0]!r}: one of {', '.join(allowed)}")
    cells = {k: cells[k] for k in kinds or allowed}  # the cells searched
    rng = np.random.default_rng(seed)
    es = None
    if optimizer == "cma":
        import cma

        # from a random point of the cube (seeded): the centre would pick one fault kind (the
        # relaxation's middle part) for every seed
        es = cma.CMAEvolutionStrategy(
            list(rng.random(len(COORDINATES))),
            0.3,
            {"bounds": [0.0, 1.0], "popsize": population, "seed": seed + 1, "verbose": -9},
        )
    t0 = time.perf_counter()
    runs, first = 0, None
    best: tuple[float, dict[str, Any], dict[str, Any]] = (math.inf, {}, {})
    history: list[tuple[int, float]] = []
    worst: dict[str, tuple[float, dict[str, Any]]] = {}
    while runs < budget and first is None:
        n = min(population, budget - runs)
        if es is not None:
            points = np.asarray(es.ask(), dtype=float)
        else:
            points = rng.random((population, len(COORDINATES)))
        # one vmapped batch per fault kind, padded to the population (one program per kind)
        built = [candidate_raw(spec, cells, level, p) for p in points[:n]]
        results = _run_candidates(spec, built, population)
        for k, (rho, fault, raw) in enumerate(results):
            if rho < best[0] or not best[1]:
                best = (rho, fault, raw)
            if fault["kind"] not in worst or rho < worst[fault["kind"]][0]:
                worst[fault["kind"]] = (rho, fault)
            if rho < 0 and first is None:
                first = runs + k + 1
        runs += n
        history.append((runs, best[0]))
        if es is not None and n == population:
            es.tell(list(points), [r if math.isfinite(r) else -1e9 for r, _, _ in results])
    return FalsifyResult(
        method=method,
        level=level,
        optimizer=optimizer,
        seed=seed,
        budget=budget,
        found=first is not None,
        runs=runs,
        runs_to_violation=first,
        best=best[0],
        fault=best[1],
        raw=best[2],
        history=history,
        seconds=time.perf_counter() - t0,
        worst=worst,
        magnitudes=(
            min_magnitudes(spec, cells, level, worst, population, rounds, seed)
            if min_magnitude
            else None
        ),
    )


def min_magnitudes(
    spec: LeagueSpec,
    cells: dict[str, Any],
    level: str,
    worst: dict[str, tuple[float, dict[str, Any]]],
    population: int = 8,
    rounds: int = 3,
    seed: int = 0,
) -> list[dict[str, Any]]:
    """The smallest severity (:data:`SEVERITY`) of each fault kind of ``cells`` that breaks the law, at
    the kind's worst run in ``worst`` (kind -> (robustness, fault)); a kind not in ``worst`` at a seeded
    random run of it. Per kind a dict: ``kind``, ``severity`` (what it is), ``largest_holding`` and
    ``smallest_violating`` (the bracket; None where no sampled severity held / broke), ``resolution``,
    ``monotone`` (the samples' robustness never rose back above 0 past a violation), ``at`` (the
    fault's channel, onset and seeds), ``runs`` and the ``samples`` (severity, robustness). A kind
    without a magnitude (stuck, outage) gets its worst run's robustness only."""
    rng = np.random.default_rng(seed)
    out: list[dict[str, Any]] = []
    for kind in (k for k in FALSIFIABLE_KINDS if k in cells):
        if kind in worst:
            rho, fault = worst[kind]
            raw = _raw_of(spec, cells, fault)
        else:  # a seeded random run of this kind
            raw, fault = candidate_raw(
                spec, {kind: cells[kind]}, level, rng.random(len(COORDINATES))
            )
            rho = math.nan
        at = {
            k: fault[k] for k in ("spacecraft", "axis", "onset", "initial_error_seed", "noise_seed")
        }
        if kind not in SEVERITY:
            out.append({"kind": kind, "severity": None, "at": at, "robustness": rho, "runs": 0})
            continue
        a, b = 0.0, 1.0  # the bracket searched
        lo: float | None = None  # the result: largest holding, smallest violating severity
        hi: float | None = None
        samples: list[tuple[float, float]] = []  # (severity, robustness), by severity
        broke: list[float] = []  # the severities that break the law
        for r in range(rounds):
            # the first round includes the ends; later ones the interior of the bracket
            grid = (
                np.linspace(a, b, population) if r == 0 else np.linspace(a, b, population + 2)[1:-1]
            )
            res = _run_candidates(
                spec, [(_with_severity(raw, fault, float(x)), fault) for x in grid], population
            )
            samples += [(float(x), rb) for x, (rb, _, _) in zip(grid, res, strict=True)]
            samples.sort()
            broke = [x for x, rb in samples if rb < 0]
            hi = broke[0] if broke else None
            held = [x for x, rb in samples if hi is None or (rb >= 0 and x < hi)]
            lo = held[-1] if held else None
            if lo is None or hi is None:
                break
            a, b = lo, hi
        monotone = not broke or all(rb < 0 for x, rb in samples if x >= broke[0])
        out.append(
            {
                "kind": kind,
                "severity": SEVERITY[kind][0],
                "largest_holding": lo,
                "smallest_violating": hi,
                "resolution": None if lo is None or hi is None else hi - lo,
                "monotone": monotone,
                "at": at,
                "runs": len(samples),
                "samples": samples,
            }
        )
    return out
