"""Mehrabian's seed study: the three FDI-imperfection cases over the seeds as one vmapped grid of runs
(cases x seeds; records decimated to the final state, metrics accumulated inside the run), a run that
leaves its admissible set replayed alone for its exact exit step, the diffusive-law variant (E003-01), and
the figure runs of one seed (a second vmapped program that keeps records every 0.1 s)."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from formation_ftc.api import build_loop, finish_run, load_scenario
from formation_ftc.components.estimators.scripted_fdi import ScriptedFdi
from formation_ftc.components.evaluations.mehrabian_metrics import metric_windows
from formation_ftc.papers.programs import jitted_run, run_loops
from formation_ftc.report.profile import phase
from formation_ftc.sim.loop import ClosedLoop

__all__ = ["CASES", "SEEDS", "FIGURE_SEED", "with_seed", "run_batch", "case_study"]

#: case letter (the paper's Cases 1-3) -> built-in scenario; paper figure.
CASES = {
    "A": ("mehrabian-no-reconfig", "3", "Case 1 (detection imperfection): no reconfiguration"),
    "B": (
        "mehrabian-identification",
        "4",
        "Case 3 (identification imperfection): reconfiguration, u* = u(t-5) - 0.1",
    ),
    "C": (
        "mehrabian-isolation",
        "5",
        "Case 2 (isolation imperfection): reconfiguration in roll, fault in yaw",
    ),
}
SEEDS = list(range(1, 21))
FIGURE_SEED = 1


def with_seed(loop: ClosedLoop, seed: int) -> ClosedLoop:
    """The same loop with every seed leaf (plant, FDI, loop) set to ``seed``.

    Parameters
    ----------
    loop : ClosedLoop
        A loop of a Mehrabian scenario (Euler-angle plant, optional scripted FDI).
    seed : int
        The run's seed [-].

    Returns
    -------
    ClosedLoop
        The loop drawing its initial attitudes, inertias, disturbances and FDI noise from ``seed``.
    """
    sd = jnp.asarray(seed, dtype=jnp.uint32)
    est = loop.estimator
    if isinstance(est, ScriptedFdi):
        est = dataclasses.replace(est, seed=sd)
    plant = dataclasses.replace(loop.plant, seed=sd)  # type: ignore[type-var]  # every plant is a @component
    return dataclasses.replace(loop, plant=plant, estimator=est, seed=sd)


def _case_loops(scenario_names: list[str], overrides: dict) -> tuple[list, list[ClosedLoop]]:
    """The scenarios ``scenario_names`` with ``overrides`` and their loops, which must share one
    compiled program."""
    scns = [load_scenario(n, overrides) for n in scenario_names]
    loops = [build_loop(s) for s in scns]
    if len({c.static_key for c in loops}) != 1:
        raise RuntimeError(
            "the Mehrabian cases must share one compiled program (static keys differ)"
        )
    return scns, loops


def run_batch(scenario_names: list[str], seeds: list[int], overrides: dict | None = None):
    """Run every (scenario, seed) pair in one vmapped program, laid out as a grid (scenarios x seeds,
    :func:`formation_ftc.papers.programs.run_loops`): a seed's measurement noise is drawn once for
    all scenarios (measured on the 3 x 20 study: run 11.4 -> 8.5 s against one flat batch, metrics bit
    for bit equal). Returns (metrics dict of arrays shaped (n_scenarios, n_seeds), diverged steps
    (n_scenarios, n_seeds))."""
    ov = dict(overrides or {})
    n_steps = load_scenario(scenario_names[0], ov).simulation.n_steps
    _, loops = _case_loops(scenario_names, {**ov, "simulation.record_every": n_steps})
    out = run_loops([with_seed(c, s) for c in loops for s in seeds], len(seeds))
    mets = {m.name: np.array(v) for m, v in zip(loops[0].metrics, out["metrics"], strict=True)}
    div = np.array(out["diverged_step"])
    # one record per run: a run that left its admissible set reports its block's first step (0) and no
    # metric; replay it alone for the exact step and its metrics up to the last record before it
    for i, k in zip(*np.nonzero(div >= 0), strict=True):
        div[i, k], m = _replay_diverged(scenario_names[i], seeds[k], ov, n_steps)
        for name, arr in mets.items():
            arr[i, k] = m[name]
    return mets, div


#: record interval [steps] of the replay of a run that left its admissible set
REPLAY_RECORD_EVERY = 100


def _replay_diverged(
    name: str, seed: int, overrides: dict, n_steps: int
) -> tuple[int, dict[str, float]]:
    """(first step outside the admissible set, metrics) of the run (``name``, ``seed``) replayed alone with
    a record every :data:`REPLAY_RECORD_EVERY` steps: the engine dates the exit exactly (replaying the
    failing record block) and freezes the metrics at the last record before it (within 1 s at
    dt = 0.01 s), so the windows that end before the exit are complete."""
    from formation_ftc.sim.engine import SimulationDiverged

    every = math.gcd(n_steps, REPLAY_RECORD_EVERY)
    s = load_scenario(
        name, {**overrides, "simulation.seed": seed, "simulation.record_every": every}
    )
    c = with_seed(build_loop(s), seed)
    out = jax.tree_util.tree_map(np.asarray, jitted_run(c)(c))
    mets = c.metric_values(out)
    try:
        finish_run(s, c, out)
    except SimulationDiverged as err:
        return int(err.info.step), mets
    return -1, mets


def _figure_runs(scenario_names: list[str], seed: int, overrides: dict | None = None):
    scns, loops = _case_loops(scenario_names, {**(overrides or {}), "simulation.seed": seed})
    # one batch of the cases (leaves shared by every run stay unbatched)
    out = run_loops([with_seed(c, seed) for c in loops])
    datasets = []
    for i, (s, c) in enumerate(zip(scns, loops, strict=True)):
        one = jax.tree_util.tree_map(lambda a, i=i: a[i], out)
        ds, _ = finish_run(s, c, one, raise_on_divergence=False)
        datasets.append(ds)
    return scns, datasets


def _stats(v: np.ndarray, unit: str, valid: np.ndarray | None = None) -> dict:
    """Mean / sample std / range over the runs that were still finite at the end of the window."""
    v = np.asarray(v, dtype=float)
    keep = np.ones(v.shape, bool) if valid is None else np.asarray(valid, bool)
    w = v[keep]
    return dict(
        mean=float(w.mean()) if w.size else None,
        std=float(w.std(ddof=1)) if w.size > 1 else (0.0 if w.size else None),
        min=float(w.min()) if w.size else None,
        max=float(w.max()) if w.size else None,
        n=int(w.size),
        n_excluded_diverged=int((~keep).sum()),
        unit=unit,
    )


def _ms(v: np.ndarray, fmt: str = ".3g") -> str:
    v = np.asarray(v, dtype=float)
    return f"{v.mean():{fmt}} +- {v.std(ddof=1) if v.size > 1 else 0.0:{fmt}} (min {v.min():{fmt}}, max {v.max():{fmt}})"


def _mx(v, extreme=np.max) -> float:
    """max (``extreme``) of an array over the runs that have a value (a run that diverged has NaN
    in-run metrics); NaN when none has: no seed qualifies, so the clause fails."""
    v = np.asarray(v, dtype=float)
    v = v[~np.isnan(v)]
    return float(extreme(v)) if v.size else float("nan")


def _mn(v) -> float:
    """min of an array over the runs that have a value (NaN when none has)."""
    return _mx(v, np.min)


def case_study(seeds: list[int], overrides: dict | None = None) -> dict[str, Any]:
    """Run the three cases over ``seeds``, the diffusive-law variant (E003-01) over the first three
    seeds and the figure runs of :data:`FIGURE_SEED`: their metrics ``M`` (arrays (case, seed)) and
    exit steps ``div`` (-1: stayed admissible), the variant's ``Md``/``divd``, the figure runs'
    scenarios and datasets, the metric windows, which runs count for each window (``valid``: still
    finite at its end) and the report's summary (statistics per case and window)."""
    names = [CASES[c][0] for c in "ABC"]
    with phase("run"):
        M, div = run_batch(names, seeds, overrides)
    with phase("run"):  # every simulation before the figures
        diffusive = {**(overrides or {}), "controller.law": "diffusive"}
        Md, divd = run_batch([CASES["A"][0], CASES["C"][0]], seeds[:3], diffusive)
    with phase("run"):
        scns, datasets = _figure_runs(names, FIGURE_SEED, overrides)
    windows = metric_windows(scns[0])
    if windows is None:
        raise ValueError(f"{names[0]}: the study needs its [[evaluations]] mehrabian-metrics")
    dt, deg = scns[0].simulation.dt, np.rad2deg
    ends = {w: b for w, (_, b) in windows.items()}
    # a run counts for a window when it was still finite at the window's end (divergence freezes the
    # accumulators at the last finite state, which may be near the singularity)
    valid = {w: (div < 0) | (div * dt >= e - 1e-9) for w, e in ends.items()}
    summary: dict = {
        "seeds": seeds,
        "units": {"sync_err": "rad", "track_err": "rad", "angles_deg": "deg"},
    }
    for i, letter in enumerate("ABC"):
        entry: dict = {"case": letter}
        for key, unit in (
            ("sync_err_rms", "rad"),
            ("track_err_rms", "rad"),
            ("sync_err_max", "rad"),
            ("track_err_max", "rad"),
            ("control_effort", "N^2 m^2 s"),
        ):
            for w in ("fault_window", "run"):
                entry[f"{key}_{w}"] = _stats(M[f"{key}_{w}"][i], unit, valid[w][i])
        for key, angle, w in (  # summary key, in-run metric over window w [rad]
            ("yaw_spread_max_45_240_deg", "spread_max_yaw", "assessment_window"),
            ("roll_spread_max_45_240_deg", "spread_max_roll", "assessment_window"),
            ("abs_yaw_max_45_240_deg", "abs_max_yaw", "assessment_window"),
            ("abs_pitch_max_fault_window_deg", "abs_max_pitch", "fault_window"),
            ("abs_pitch_max_run_deg", "abs_max_pitch", "run"),
        ):
            entry[key] = _stats(deg(M[f"{angle}_{w}"][i]), "deg", valid[w][i])
        entry["diverged_runs"] = [
            {"seed": int(seeds[k]), "time_s": float(div[i, k] * dt)}
            for k in np.flatnonzero(div[i] >= 0)
        ]
        summary[names[i]] = entry
    roll_d = deg(Md["spread_max_roll_assessment_window"])
    summary["diffusive_law_roll_spread_max_45_240_deg"] = {
        CASES[c][0]: _stats(roll_d[j], "deg", divd[j] < 0) for j, c in enumerate("AC")
    }
    return dict(
        M=M, div=div, Md=Md, divd=divd, scenarios=scns, datasets=datasets, windows=windows
    ) | dict(valid=valid, ends=ends, summary=summary)
