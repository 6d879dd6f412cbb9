"""Gui2022 benchmark: the ILO / LOF2TC loops (dt = 1 ms, 3 million steps per 3,000 s run).

Prints, in one run (medians of ``--repeats``; timings on shared machines are noisy, compare ratios or
the process CPU time, the least of the repeats, which a loaded machine inflates less):

* the plain-numpy per-step loop of the same closed loop (``papers/gui2022/numpy_reference.py``) on a
  short horizon (``--numpy-horizon``, default 20 s), in us/step;
* the JAX scan (``run_fixed_step``) of the same scenario for ``unroll`` in ``--unrolls``, compile time and
  us/step on the full horizon, and the ratio numpy / JAX per step;
* the full-horizon wall time of each built-in scenario (issue 4 target: < 10 s after compilation) and the
  peak RSS of the process (target < 2 GiB).

Run: ``python benchmarks/gui2022.py [--horizon 3000] [--unrolls 1,5,10] [--repeats 3]``
"""

from __future__ import annotations

import argparse
import resource
import statistics
import time


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--horizon", type=float, default=3000.0, help="JAX run horizon [s]")
    ap.add_argument("--numpy-horizon", type=float, default=20.0, help="numpy loop horizon [s]")
    ap.add_argument("--unrolls", default="1,5,10")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)

    import jax

    import formation_ftc as ftc
    from formation_ftc.api import build_loop
    from formation_ftc.papers.gui2022.numpy_reference import simulate_numpy

    jax.config.update("jax_compilation_cache_dir", None)  # measure real compile times

    def time_jax(name, horizon, unroll):
        scn = ftc.load_scenario(name, {"simulation.horizon": horizon, "simulation.unroll": unroll})
        c = build_loop(scn)
        t0 = time.perf_counter()
        f = jax.jit(type(c).run).lower(c).compile()
        tc = time.perf_counter() - t0
        ts, cpu = [], []
        for _ in range(args.repeats):
            t0, p0 = time.perf_counter(), time.process_time()
            jax.block_until_ready(f(c))
            ts.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - p0)
        return tc, statistics.median(ts), scn.simulation.n_steps, min(cpu)

    print(
        f"gui2022 benchmark: JAX horizon {args.horizon:g} s, numpy horizon {args.numpy_horizon:g} s, "
        f"dt = 1 ms, devices {jax.devices()}"
    )
    rows = []
    for name in ("gui2022-ilo", "gui2022-lof2tc"):
        scn = ftc.load_scenario(name, {"simulation.horizon": args.numpy_horizon})
        ts = []
        for _ in range(max(1, args.repeats // 2)):
            t0 = time.perf_counter()
            simulate_numpy(scn)
            ts.append(time.perf_counter() - t0)
        us_np = statistics.median(ts) / scn.simulation.n_steps * 1e6
        print(
            f"  {name:16s} numpy loop      : {us_np:8.2f} us/step "
            f"(3e6 steps would take {us_np * 3:.0f} s)"
        )
        for u in (int(x) for x in args.unrolls.split(",")):
            tc, tr, n, cpu = time_jax(name, args.horizon, u)
            us = tr / n * 1e6
            print(
                f"  {name:16s} JAX unroll={u:<3d}: {us:8.3f} us/step, run {tr:6.2f} s for {n} steps "
                f"(CPU time {cpu:6.2f} s), compile {tc:5.1f} s, numpy/JAX = {us_np / us:6.1f}x"
            )
            rows.append((name, u, tr, tc))
    print("full runs of the built-in scenarios (their own unroll):")
    for name in ("gui2022-ilo", "gui2022-ilo-baseline", "gui2022-lof2tc", "gui2022-cof2tc"):
        scn = ftc.load_scenario(name, {"simulation.horizon": args.horizon})
        tc, tr, n, cpu = time_jax(name, args.horizon, scn.simulation.unroll)
        print(
            f"  {name:22s}: run {tr:6.2f} s (CPU time {cpu:6.2f} s; {n} steps, target < 10 s), "
            f"compile {tc:5.1f} s"
        )
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak RSS of this process: {rss:.0f} MiB (target < 2048 MiB)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
