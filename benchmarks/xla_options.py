"""Cost per step of the package's XLA:CPU compile options against XLA's default build, in one run.

For each case the same lowered program is compiled twice -- with XLA's defaults (the reference) and
with :func:`formation_ftc.sim.runtime.xla.compiler_options` as the package compiles it -- and both executables
are timed alternately (fastest of ``--repeats``; a shared 2-core machine varies by 10-40 % between
single passes). Printed: microseconds per run-step of each, their ratio (package / default; < 1 is
faster), the compile times, and whether the two results agree bit for bit (else the largest relative
difference of the final state and metrics).

Cases: the Mehrabian seed-study batch (3 cases x 20 seeds, 8 spacecraft; fast-compile preset), and
single runs of li2020-thm1, azizi2009-llfr and gui2022-ilo.

Run: ``python benchmarks/xla_options.py [--horizon-scale 1.0] [--repeats 3]``. Exit status 0 always
(a measurement, not a gate).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

os.environ.setdefault("FORMATION_FTC_JAX_CACHE", "off")  # every compile measured cold

import jax  # noqa: E402
import numpy as np  # noqa: E402

from formation_ftc.api import build_loop, load_scenario  # noqa: E402
from formation_ftc.sim.runtime import xla  # noqa: E402


def _mehrabian(scale: float):
    from formation_ftc.papers.mehrabian.seed_study import CASES, with_seed
    from formation_ftc.sim.batch import stack_params

    names = [CASES[c][0] for c in "ABC"]
    ov = {"simulation.horizon": 20.0 * scale}
    n = load_scenario(names[0], ov).simulation.n_steps
    comp = [build_loop(load_scenario(x, {**ov, "simulation.record_every": n})) for x in names]
    params, axes = stack_params([with_seed(c, s) for c in comp for s in range(1, 21)])
    size = 3 * 20
    run = type(comp[0]).run
    fn = jax.vmap(lambda p: dict(run(p)), in_axes=(axes,), axis_size=size)
    fast = bool(getattr(comp[0].controller, "batch_fast_compile", False))
    return "mehrabian seed study (60 runs x 8 spacecraft)", fn, params, size * n, fast


def _single(name: str, horizon: float):
    def make(scale: float):
        c = build_loop(load_scenario(name, {"simulation.horizon": horizon * scale}))
        return f"{name} (single run)", type(c).run, c, c.n_steps, False

    return make


CASES = [
    _mehrabian,
    _single("li2020-thm1", 30.0),
    _single("azizi2009-llfr", 60.0),
    _single("gui2022-ilo", 100.0),
]


def _leaves(out) -> np.ndarray:
    tree = {"final": out["final"], "metrics": out["metrics"]}
    return np.concatenate(
        [
            np.ravel(np.asarray(x, dtype=float))
            for x in jax.tree_util.tree_leaves(tree)
            if np.asarray(x).dtype.kind in "fiu"
        ]
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--horizon-scale", type=float, default=1.0, help="scale every case's horizon")
    ap.add_argument("--repeats", type=int, default=3, help="alternate timed passes per executable")
    args = ap.parse_args(argv)
    print(
        f"{'case':48s} {'default':>10s} {'package':>10s} {'ratio':>6s}  compile default / package   same"
    )
    for case in CASES:
        label, fn, params, run_steps, fast = case(args.horizon_scale)
        lowered = jax.jit(fn).lower(params)
        exes, compile_s = [], []
        for opts in ({}, xla.compiler_options(fast_compile=fast)):
            t0 = time.perf_counter()
            exes.append(lowered.compile(compiler_options=opts) if opts else lowered.compile())
            compile_s.append(time.perf_counter() - t0)
        outs = [jax.device_get(jax.block_until_ready(e(params))) for e in exes]
        best = [float("inf")] * 2
        for _ in range(args.repeats):
            for i, e in enumerate(exes):
                t0 = time.perf_counter()
                jax.block_until_ready(e(params))
                best[i] = min(best[i], time.perf_counter() - t0)
        a, b = _leaves(outs[0]), _leaves(outs[1])
        fin = np.isfinite(a) & np.isfinite(b)
        same = np.array_equal(a[fin], b[fin]) and np.array_equal(np.isfinite(a), np.isfinite(b))
        rel = (
            0.0
            if same
            else float(np.max(np.abs(a[fin] - b[fin]) / np.maximum(np.abs(a[fin]), 1e-300)))
        )
        us = [t / run_steps * 1e6 for t in best]
        print(
            f"{label:48s} {us[0]:8.3f}us {us[1]:8.3f}us {us[1] / us[0]:6.3f}  {compile_s[0]:6.2f} s / "
            f"{compile_s[1]:6.2f} s   {'bitwise' if same else f'max rel diff {rel:.1e}'}",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
