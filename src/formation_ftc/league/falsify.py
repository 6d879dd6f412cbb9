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
(robustness < 0) or at the run budget, and report the runs to it.
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

__all__ = ["COORDINATES", "FALSIFIABLE_KINDS", "candidate_raw", "falsify", "FalsifyResult"]

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


def _pick(u: float, n: int) -> int:
    return min(int(u * n), n - 1)


def _mix(lo: float, hi: float, u: float, log: bool = False) -> float:
    if log:
        return float(math.exp(math.log(lo) + u * (math.log(hi) - math.log(lo))))
    return float(lo + u * (hi - lo))


def candidate_raw(
    spec: LeagueSpec, cells: dict[str, Any], level: str, u: np.ndarray
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The full scenario of the point ``u`` of the unit cube (:data:`COORDINATES`) on the method's
    cells ``cells`` (kind -> its league cell at ``level``), and the fault it draws (JSON-able)."""
    u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
    x = dict(zip(COORDINATES, u, strict=True))
    kinds = [k for k in FALSIFIABLE_KINDS if k in cells]
    kind = kinds[_pick(x["kind"], len(kinds))]
    raw = copy.deepcopy(cells[kind].raw)
    act = raw["actuator"]
    n = len(spec.truth.get("mass", [])) or len(spec.truth.get("initial_attitude_deg", [])) or 4
    on = spec.league.onset
    fault: dict[str, Any] = {
        "kind": kind,
        "spacecraft": _pick(x["spacecraft"], n) + 1,
        "axis": _pick(x["axis"], 3),
        "onset": _mix(on.low, on.high, x["onset"]),
    }
    limit = act.get("saturation")
    bias = float(limit) if limit is not None else 1.0  # the level's limit, or the battery's 1 N
    if kind == "loss_of_effectiveness":
        fault["effectiveness"] = _mix(0.0, 1.0, x["effectiveness"])
    elif kind == "bias":
        fault["bias"] = _mix(-bias, bias, x["bias"])
    elif kind == "intermittent":
        fault["period"] = _mix(10.0, 200.0, x["period"])
        fault["duty"] = _mix(0.1, 0.9, x["duty"])
    elif kind == "degrading":
        fault["rate"] = _mix(1e-4, 1e-2, x["rate"], log=True)
        fault["min_effectiveness"] = _mix(0.0, 1.0, x["min_effectiveness"])
    act.update({k: v for k, v in fault.items() if k != "kind"})
    seeds = {
        "initial_error_seed": _pick(x["initial_error"], SEEDS),
        "noise_seed": _pick(x["noise"], SEEDS),
    }
    field = str(spec.league.initial_error.seed_field).removeprefix("plant.")
    raw["plant"][field] = seeds["initial_error_seed"]
    raw["simulation"]["seed"] = seeds["noise_seed"]
    if spec.league.onset.field != "actuator.onset":
        raise LeagueError(
            f"league.onset.field = {spec.league.onset.field!r}: falsify needs actuator.onset"
        )
    return raw, {**fault, **seeds}


def _robustness(spec: LeagueSpec, metrics: dict[str, float], diverged: bool) -> float:
    """The run's requirement robustness (>= 0: it passes)."""
    if diverged:
        return -math.inf
    if spec.league.requirement.stl is not None:
        return -float(metrics[STL_VIOLATION])
    return float(spec.league.requirement.max) - float(metrics[spec.league.requirement.metric])


def _evaluate(spec, cells, level, points: np.ndarray, size: int) -> list[tuple[float, dict, dict]]:
    """(robustness, fault, raw) of every point, in order: one vmapped batch per fault kind, padded to
    ``size`` runs (the same compiled program for every population)."""
    import jax

    from formation_ftc import api
    from formation_ftc.sim.batch import batched_run, stack_params

    built = [candidate_raw(spec, cells, level, p) for p in points]
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
    ``history`` of (runs, best robustness) after every population."""

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
) -> FalsifyResult:
    """Search ``method`` at ``level`` of ``league`` for a run that violates the requirement, with at
    most ``budget`` runs (``population`` per batch), by CMA-ES from a random point (step 0.3) or
    uniform random sampling; ``seed`` seeds the optimiser. ``step_checks`` (a league's ``league.json``
    record): fly the method at the step its league check chose (default: run the check)."""
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
    if not any(k in cells for k in FALSIFIABLE_KINDS):
        raise LeagueError(f"method {method} has no actuator-fault cell at level {level}")
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
    while runs < budget and first is None:
        n = min(population, budget - runs)
        if es is not None:
            points = np.asarray(es.ask(), dtype=float)
        else:
            points = rng.random((population, len(COORDINATES)))
        results = _evaluate(spec, cells, level, points[:n], population)
        for k, (rho, fault, raw) in enumerate(results):
            if rho < best[0] or not best[1]:
                best = (rho, fault, raw)
            if rho < 0 and first is None:
                first = runs + k + 1
        runs += n
        history.append((runs, best[0]))
        if es is not None and n == population:
            finite = [r if math.isfinite(r) else -1e9 for r, _, _ in results]
            es.tell(list(points), finite)
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
    )
