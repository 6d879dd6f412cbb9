"""Grids of runs (``formation_ftc.sim.batch.batched_grid_run``: two nested ``jax.vmap``) against one
flat batch of the same runs (``batched_run``: one ``jax.vmap``, the plain reference), in one process.

A study that crosses seeds with another parameter draws, in a flat batch, the same measurement noise
once per run; on a grid the seed is a row (or column) leaf, batched by one of the two maps only, and
its draws are made once per seed. Cases, as the reproductions run them:

* Azizi2009's seed study: 20 seeds (rows) x 12 weights alpha_2 (columns), measurement noise on, at a
  reduced horizon (``--horizon``, default 30 s of the paper's 300 s, i.e. 30,000 steps);
* Mehrabian's study: 3 cases (rows) x 20 seeds (columns), at ``--mehrabian-scale`` of its horizon.

Both programs are compiled with the persistent cache off and run alternately (fastest of
``--repeats``; a shared 2-core machine varies by 10-40 % between single passes). Printed per case:
compile and run time of each, the ratio grid / flat (< 1: the grid is faster), and whether every
metric is bit for bit the same.

Run: ``python benchmarks/grid_batch.py [--horizon 30] [--mehrabian-scale 0.25] [--repeats 3]``. Exit
status 0 always (a measurement, not a gate).
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("FORMATION_FTC_JAX_CACHE", "off")  # every compile measured cold

import jax  # noqa: E402
import numpy as np  # noqa: E402

from formation_ftc.api import build_loop, load_scenario  # noqa: E402
from formation_ftc.sim import batch as batch_programs  # noqa: E402
from formation_ftc.sim.batch import batched_grid_run, batched_run, stack_params, stack_params_grid  # noqa: E402


def _azizi(horizon: float):
    from formation_ftc.methods.composed import make_loop
    from formation_ftc.papers._study import read_study
    from formation_ftc.papers.azizi2009.alpha2_study import _variant

    _c = read_study("azizi2009")["reproduction"]["constants"]
    NOISE_SIGMA, SEEDS = _c["noise_sigma"], _c["seeds"]

    sc = load_scenario(
        "azizi2009-llfr",
        {
            "simulation.horizon": horizon,
            "plant.axes": 1,
            "simulation.record_every": 1000,
            "sensors.position_noise_std": NOISE_SIGMA,
            "sensors.velocity_noise_std": NOISE_SIGMA,
        },
    )
    loop = make_loop(sc)
    weights = np.round(np.concatenate([[1.0], 4.5 + 0.1 * np.arange(-5, 6)]), 10)
    grid = [
        [_variant(loop, {"alpha": [1.0, w, 1.0, 1.0], "seed": s}) for w in weights]
        for s in range(SEEDS)
    ]
    return loop.validate(), grid


def _mehrabian(scale: float):
    from formation_ftc.papers.mehrabian.seed_study import CASES, SEEDS, with_seed

    names = [CASES[c][0] for c in "ABC"]
    base = load_scenario(names[0])
    n = max(1, round(scale * base.simulation.n_steps))
    ov = {"simulation.horizon": n * base.simulation.dt, "simulation.record_every": n}
    compiled = [build_loop(load_scenario(name, ov)) for name in names]
    return compiled[0], [[with_seed(c, s) for s in SEEDS] for c in compiled]


def _time(fn, args) -> tuple[float, float, object]:
    t0 = time.perf_counter()
    exe = fn.lower(args).compile()
    t1 = time.perf_counter()
    out = jax.device_get(exe(args))
    return t1 - t0, time.perf_counter() - t1, out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--horizon", type=float, default=30.0, help="Azizi2009 horizon [s] (paper: 300)"
    )
    ap.add_argument(
        "--mehrabian-scale", type=float, default=0.25, help="fraction of the Mehrabian horizon"
    )
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    cases = {
        "azizi2009 seeds x weights": _azizi(args.horizon),
        "mehrabian cases x seeds": _mehrabian(args.mehrabian_scale),
    }
    print(
        f"{'case':28s} {'runs':>5s} {'compile flat/grid [s]':>22s} {'run flat/grid [s]':>20s} {'ratio':>6s}  bitwise"
    )
    for name, (compiled, grid) in cases.items():
        rows, cols = len(grid), len(grid[0])
        flat_batch, axes = stack_params([p for row in grid for p in row])
        grid_batch, row_axes, col_axes = stack_params_grid(grid)
        best = {"flat": [np.inf, np.inf], "grid": [np.inf, np.inf]}
        outs = {}
        for _ in range(args.repeats):
            jax.clear_caches()
            for kind in ("flat", "grid"):
                batch_programs.clear()  # a fresh program each repeat: the compile is timed too
                fn = (
                    batched_run(compiled, axes, rows * cols)
                    if kind == "flat"
                    else batched_grid_run(compiled, row_axes, col_axes, rows, cols)
                )
                c, r, out = _time(fn, flat_batch if kind == "flat" else grid_batch)
                best[kind] = [min(best[kind][0], c), min(best[kind][1], r)]
                outs[kind] = out
        flat_m = [np.asarray(v) for v in outs["flat"]["metrics"]]
        grid_m = [
            np.asarray(v).reshape((rows * cols,) + np.shape(v)[2:]) for v in outs["grid"]["metrics"]
        ]
        same = all(
            np.array_equal(a, b, equal_nan=True) for a, b in zip(flat_m, grid_m, strict=True)
        )
        print(
            f"{name:28s} {rows * cols:5d} {best['flat'][0]:10.2f} / {best['grid'][0]:5.2f} "
            f"{best['flat'][1]:12.2f} / {best['grid'][1]:5.2f} {best['grid'][1] / best['flat'][1]:6.2f}  {same}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
