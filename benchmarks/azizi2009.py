"""Azizi2009 benchmark: the alpha_2 sweep of the reproduction as one batch (sim.batch) and single runs.

Prints (medians of ``--repeats``; timings on shared machines are noisy, compare the CPU seconds):

* the alpha_2 sweep (``--runs`` weights on 1 ... 10, x axis only, ``--horizon`` s at dt = 1 ms) through
  :func:`formation_ftc.papers.azizi2009.reproduction.run_batch`: compile time, wall and process CPU time per
  call, run-steps per second;
* the single run of each built-in scenario (3 axes) over ``--horizon``: wall time after compilation.

Run: ``python benchmarks/azizi2009.py [--horizon 100] [--runs 91] [--repeats 3]``
"""

from __future__ import annotations

import argparse
import statistics
import time


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--horizon", type=float, default=100.0, help="run horizon [s]")
    ap.add_argument("--runs", type=int, default=91, help="alpha_2 grid size of the sweep")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)

    import jax
    import numpy as np

    from formation_ftc.api import build_loop, load_scenario
    from formation_ftc.papers.azizi2009.alpha2_study import run_batch

    sc = load_scenario(
        "azizi2009-llfr",
        {
            "simulation.horizon": args.horizon,
            "plant.axes": 1,
            "simulation.record_every": 1000,
        },
    )
    A = np.ones((args.runs, 4))
    A[:, 1] = np.linspace(1.0, 10.0, args.runs)
    t0 = time.perf_counter()
    run_batch(sc, {"alpha": A})
    first = time.perf_counter() - t0
    walls, cpus = [], []
    for _ in range(args.repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        run_batch(sc, {"alpha": A})
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    w, c = statistics.median(walls), statistics.median(cpus)
    steps = args.runs * sc.simulation.n_steps
    print(f"azizi2009 benchmark: horizon {args.horizon:g} s, dt = 1 ms, devices {jax.devices()}")
    print(
        f"alpha_2 sweep, {args.runs} runs x {sc.simulation.n_steps} steps: first call (compile + run) "
        f"{first:.2f} s, then wall {w:.2f} s, CPU {c:.2f} s, {steps / w:.3g} run-steps/s"
    )
    for name in ("azizi2009-fault-free", "azizi2009-llfr", "azizi2009-flfr"):
        c_ = build_loop(load_scenario(name, {"simulation.horizon": args.horizon}))
        f = jax.jit(type(c_).run).lower(c_).compile()
        ts = []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            jax.block_until_ready(f(c_))
            ts.append(time.perf_counter() - t0)
        print(f"{name}: {statistics.median(ts):.2f} s per run after compilation")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
