"""Metrics folded a block of steps at a time (``ClosedLoop.metric_block``) against the plain reference,
the sample-by-sample fold at every step (``metric_block = 1``), in one process.

A closed loop accumulates its metrics inside the compiled run. At every step, each metric group is a
few small kernels (its value: a norm, a component; its update: a max, a sum, a settling test); with
tens of metrics they cost more than the dynamics of a 6-state plant. Folded, the step writes the
signals the metrics read into a buffer, and every L steps the values and reductions of the whole block
are computed at once.

Printed per case: compile time, time per step (fastest of ``--repeats``), the ratio folded / per step
(< 1: folding is faster) and the largest relative difference of the metrics (the sums add in another
order; selections pick the same sample). Cases:

* single runs of the Gui2022 scenarios (28-42 metrics, records every 100 steps): the automatic choice
  folds these, in blocks of 50;
* single runs of li2020-thm1 (15 step metrics, records every 10 steps) and azizi2009-llfr (7), and a
  vmapped batch of 16 azizi2009-llfr runs, folded in blocks of 10 / 50: the automatic choice keeps the
  per-step fold for these (few metrics, short blocks; under ``vmap`` a step's kernels already serve
  the whole batch) -- the figures show why.

Run: ``python benchmarks/metric_fold.py [--horizon 300] [--repeats 3]`` (horizon in s; the Gui2022 and
Azizi2009 runs step 1 ms, Li2020 10 ms). Exit status 0 always (a measurement, not a gate).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time

os.environ.setdefault("FORMATION_FTC_JAX_CACHE", "off")  # every compile measured cold

import jax  # noqa: E402
import numpy as np  # noqa: E402

from formation_ftc.api import build_loop, load_scenario  # noqa: E402
from formation_ftc.sim.batch import stack_params  # noqa: E402
from formation_ftc.sim.metrics import metrics_dict  # noqa: E402


def _timed(fn, arg, repeats: int) -> tuple[float, float, dict]:
    """(compile s, fastest run s, output) of ``jax.jit(fn)(arg)``."""
    t0 = time.perf_counter()
    compiled = jax.jit(fn).lower(arg).compile()
    compile_s = time.perf_counter() - t0
    out = jax.block_until_ready(compiled(arg))
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(compiled(arg))
        best = min(best, time.perf_counter() - t0)
    return compile_s, best, out


def _per_run(metrics_out, runs: int) -> list[list[np.ndarray]]:
    """A run's metric values (one array per metric) for each run of a (possibly batched) output."""
    leaves = [np.asarray(x) for x in metrics_out]
    return [leaves] if runs == 1 else [[x[r] for x in leaves] for r in range(runs)]


def _worst(metrics, a, b) -> float:
    """Largest relative difference between two runs' metrics (NaN where both are NaN counts as equal)."""
    da, db = metrics_dict(metrics, a), metrics_dict(metrics, b)
    worst = 0.0
    for k, x in da.items():
        y = db[k]
        if np.isnan(x) and np.isnan(y):
            continue
        worst = max(worst, abs(x - y) / max(abs(x), 1e-300))
    return worst


def _single(loop):
    return loop.run()["metrics"]


def _batched(axes):
    def fn(batch):
        return jax.vmap(_single, in_axes=(axes,))(batch)

    return fn


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--horizon", type=float, default=300.0, help="simulated time of every run [s]")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()

    cases = [
        ("gui2022-lof2tc", 50, 1),
        ("gui2022-ilo", 50, 1),
        ("gui2022-cof2tc", 50, 1),
        ("li2020-thm1", 10, 1),
        ("azizi2009-llfr", 50, 1),
        ("azizi2009-llfr", 50, 16),
    ]
    print(
        f"metric fold: blocks of L steps vs every step; {args.horizon:g} s per run, fastest of {args.repeats}; "
        "a batch's time per step is that of all its runs"
    )
    print(
        f"{'scenario':22s} {'runs':>4s} {'L':>3s} {'auto':>4s}  {'compile step/fold [s]':>22s}  "
        f"{'per step: step/fold [us]':>25s}  {'ratio':>5s}  {'max rel diff':>12s}"
    )
    for name, block, runs in cases:
        ov = {"simulation.horizon": args.horizon}
        loop = build_loop(load_scenario(name, ov))
        n = loop.n_steps
        if (
            runs > 1
        ):  # a sweep of the second actuator's weight alpha_2 from 1 to 10, as the reproduction's
            loops = [
                build_loop(load_scenario(name, {**ov, "controller.alpha": [1.0, a, 1.0, 1.0]}))
                for a in np.linspace(1.0, 10.0, runs)
            ]
            batch, axes = stack_params([dataclasses.replace(p, metric_block=1) for p in loops])
            batch_fold, axes_fold = stack_params(
                [dataclasses.replace(p, metric_block=block) for p in loops]
            )
            stepwise, folded = batch, batch_fold
            fn_step, fn_fold = (_batched(a) for a in (axes, axes_fold))
        else:
            stepwise, folded = (
                dataclasses.replace(loop, metric_block=1),
                dataclasses.replace(loop, metric_block=block),
            )
            fn_step = fn_fold = _single
        c_step, t_step, m_step = _timed(fn_step, stepwise, args.repeats)
        c_fold, t_fold, m_fold = _timed(fn_fold, folded, args.repeats)
        diff = max(
            _worst(loop.metrics, a, b)
            for a, b in zip(_per_run(m_step, runs), _per_run(m_fold, runs), strict=True)
        )
        auto = loop._metric_block()
        print(
            f"{name:22s} {runs:4d} {block:3d} {auto:4d}  {c_step:10.2f} / {c_fold:9.2f}  "
            f"{t_step / n * 1e6:12.3f} / {t_fold / n * 1e6:10.3f}  {t_fold / t_step:5.2f}  {diff:12.1e}",
            flush=True,
        )


if __name__ == "__main__":
    main()
