"""The league's step-convergence check: each method's integration step is chosen, not assumed.

Before a method's campaign, the league runs one check cell (``[league.step_check]``: a fault case and a
level; the nominal initial errors and the earliest fault onset) at the method's own step ``dt`` and at
``dt / 2``. When every score of the league (its ``[[metrics]]``, per spacecraft included) changes by at
most ``tolerance`` (relative, 2 % by default) the step is kept; otherwise the step is halved and the
comparison repeated: the chosen step may be down to ``dt / 2**max_halvings`` (the finest run is at
``dt / 2**(max_halvings + 1)``). The chosen step is the coarser step of the first pair
that agrees; when no pair agrees the method keeps its own step and the league records it as *not
converged* (the leaderboard says so next to the method's effort scores).

The check runs with the sensors' and the plant's noise switched off (every ``*_noise_std`` field of
``[sensors]`` and the plant's ``process_noise_std`` set to 0): a noise sample is held over one step, so
its effect on a high-gain law depends on the step by construction -- that is a property of the sensor
model, not an integration error, and it would hide the integration error the check is for. Everything
it measured is written to ``league.json`` (``step_check``: per method, every step tried, the scores at
each, the largest relative change and the chosen step).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from typing import Any

__all__ = ["StepCheckResult", "check_step", "scores_agree", "quiet_cell"]


@dataclass
class StepCheckResult:
    """What the check measured for one method (JSON-ready through :meth:`as_dict`)."""

    method: str
    case: str
    level: str
    tolerance: float
    steps: list[float]  # every step tried [s], coarsest first
    scores: list[dict[str, float]]  # the league's scores at each step
    changes: list[float] = field(default_factory=list)  # largest relative change, step k vs k + 1
    worst: list[str] = field(default_factory=list)  # the score that changed most, step k vs k + 1
    converged: bool = False
    chosen_dt: float = 0.0  # [s]

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def scores_agree(a: dict[str, float], b: dict[str, float], tolerance: float) -> tuple[float, str]:
    """The largest relative change between two runs' scores and its name.

    ``|a - b| / max(|a|, |b|)`` over every score present in both (a change below 1e-9 in absolute value
    counts as none: a zero score that stays zero to rounding). Two NaNs agree (a score with no sample in
    either run); a NaN in one run only is an infinite change.

    Examples
    --------
    >>> scores_agree({"x": 1.0, "y": 0.0}, {"x": 1.01, "y": 0.0}, 0.02)
    (0.00990099009900991, 'x')
    """
    worst, name = 0.0, ""
    for key in sorted(set(a) & set(b)):
        x, y = float(a[key]), float(b[key])
        if math.isnan(x) and math.isnan(y):
            continue
        if math.isnan(x) or math.isnan(y):
            change = math.inf
        elif abs(x - y) <= 1e-9:
            change = 0.0
        else:
            change = abs(x - y) / max(abs(x), abs(y))
        if change > worst:
            worst, name = change, key
    return worst, name


def quiet_cell(raw: dict[str, Any], onset_field: str, onset: float) -> dict[str, Any]:
    """The cell's scenario with its noise off and the fault onset at ``onset`` [s] (see module doc)."""
    out = copy.deepcopy(raw)
    for key in list(out.get("sensors", {})):
        if key.endswith("_noise_std"):
            out["sensors"][key] = 0.0
    if "process_noise_std" in out.get("plant", {}):
        out["plant"]["process_noise_std"] = 0.0
    node: Any = out
    *parents, leaf = onset_field.split(".")
    for part in parents:
        node = node.get(part) if isinstance(node, dict) else None
    if isinstance(node, dict):
        node[leaf] = onset
    return out


def check_step(
    method: str,
    raw: dict[str, Any],
    *,
    case: str,
    level: str,
    onset_field: str,
    onset: float,
    tolerance: float = 0.02,
    max_halvings: int = 3,
    ignore: tuple[str, ...] = (),
    on_simulation: Callable[[float, bool], None] | None = None,
) -> StepCheckResult:
    """Choose ``method``'s step on the check cell ``raw`` (a full composed scenario, see module doc).

    Parameters
    ----------
    method : str
        The method's name (for the record).
    raw : dict
        The check cell's scenario (the league writes one per cell).
    case, level : str
        The fault case and level of ``raw`` (for the record).
    onset_field : str
        Dotted path of the fault onset in ``raw``; ``onset`` [s] is written there.
    tolerance : float
        Largest relative change of any score when the step halves [-].
    max_halvings : int
        How many times the step may be halved before the check gives up.
    ignore : tuple of str
        Scores left out of the comparison (e.g. a fault detector's alarm times, which are on the step
        grid by construction: a detection in the fault's first step has a delay of one step).
    on_simulation : callable, optional
        Called with ``(dt, False)`` before and ``(dt, True)`` after each simulation of the check
        (progress).

    Returns
    -------
    StepCheckResult
        Every step tried, the scores at each, and the chosen step.
    """
    from formation_ftc.api import load_scenario, simulate_with_metrics

    base = quiet_cell(raw, onset_field, onset)
    notify = on_simulation or (lambda dt, finished: None)

    def scores(dt: float) -> dict[str, float]:
        cell = copy.deepcopy(base)
        cell["simulation"]["dt"] = dt
        notify(dt, False)
        _, metrics = simulate_with_metrics(load_scenario(cell), raise_on_divergence=False)
        notify(dt, True)
        return {k: float(v) for k, v in metrics.items() if k not in ignore}

    dt = float(base["simulation"]["dt"])
    result = StepCheckResult(method, case, level, tolerance, [dt], [scores(dt)], chosen_dt=dt)
    for _ in range(max_halvings + 1):
        dt = result.steps[-1]
        result.steps.append(dt / 2.0)
        result.scores.append(scores(dt / 2.0))
        change, name = scores_agree(result.scores[-2], result.scores[-1], tolerance)
        result.changes.append(change)
        result.worst.append(name)
        if change <= tolerance:
            result.converged, result.chosen_dt = True, dt
            break
    return result
