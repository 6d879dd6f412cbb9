"""CPU client thread pool: one thread (``PJRT_NPROC=1``) against JAX's default, one per core.

XLA:CPU runs the independent operations of a program side by side on its CPU client's thread pool. A
closed-loop step is a chain of many operations on a few numbers each, so the hand-over between threads
can cost more than the operations. For each case this script runs the same compiled program in two
fresh processes, one with ``PJRT_NPROC=1`` and one with ``PJRT_NPROC=<cores>`` (JAX's own default), and
prints the best-of-``--repeats`` wall and CPU time of the run (compilation excluded), their ratios, and
whether the two processes computed the same numbers (a SHA-256 digest of every output leaf's bytes).

The package leaves a single process at JAX's default. Where processes share the cores -- the paper
workers of ``formation-ftc reproduce`` and the pytest-xdist workers of the test suite -- each gets the
cores divided by the number of processes (one on 2 cores). The pool size also reaches the compiled
program (XLA partitions some loops by it), so the persistent compilation cache keeps one directory per
thread count (``formation_ftc.sim.runtime.compilation_cache_dir``).

Run: ``python benchmarks/cpu_threads.py [--repeats 3] [--cases gui2022-lof2tc:300,li2020-thm1:100]``
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

#: scenario:horizon [s] pairs measured by default (single runs of each paper's step)
DEFAULT_CASES = (
    "gui2022-lof2tc:300,li2020-thm2-delays:100,mehrabian-isolation:100,azizi2009-llfr:300"
)

_CHILD = """
import hashlib, json, resource, sys, time
import jax, numpy as np
from formation_ftc.api import build_loop, load_scenario
from formation_ftc.sim.runtime import xla
name, horizon, repeats = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
c = build_loop(load_scenario(name, {"simulation.horizon": horizon}))
run = xla.jit(type(c).run).lower(c).compile()
out = jax.block_until_ready(run(c))
best_wall, best_cpu = float("inf"), float("inf")
for _ in range(repeats):
    r0 = resource.getrusage(resource.RUSAGE_SELF)
    t0 = time.perf_counter()
    out = jax.block_until_ready(run(c))
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_SELF)
    best_wall = min(best_wall, wall)
    best_cpu = min(best_cpu, r1.ru_utime + r1.ru_stime - r0.ru_utime - r0.ru_stime)
digest = hashlib.sha256()
for leaf in jax.tree_util.tree_leaves(out):
    digest.update(np.ascontiguousarray(leaf).tobytes())
print(json.dumps({"wall": best_wall, "cpu": best_cpu, "digest": digest.hexdigest()}))
"""


def _measure(name: str, horizon: float, threads: int, repeats: int) -> dict:
    env = dict(os.environ, PJRT_NPROC=str(threads), FORMATION_FTC_JAX_CACHE="off")
    proc = subprocess.run(
        [sys.executable, "-c", _CHILD, name, str(horizon), str(repeats)],
        capture_output=True,
        text=True,
        env=env,
        timeout=1800,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"{name} with PJRT_NPROC={threads} failed:\n{proc.stderr[-2000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default=DEFAULT_CASES, help="comma-separated scenario:horizon pairs")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    cores = os.cpu_count() or 1
    print(
        f"run time (compile excluded), best of {args.repeats}; 1 pool thread vs {cores} (one per core)"
    )
    print(
        f"  {'case':32s} {'1 thread: wall / CPU':>22s} {f'{cores} threads: wall / CPU':>24s}"
        f" {'wall ratio':>10s} {'CPU ratio':>10s}  same numbers"
    )
    for case in args.cases.split(","):
        name, horizon = case.rsplit(":", 1)
        one = _measure(name, float(horizon), 1, args.repeats)
        many = _measure(name, float(horizon), cores, args.repeats)
        print(
            f"  {name + ' (' + horizon + ' s)':32s} {one['wall']:9.3f} / {one['cpu']:7.3f} s "
            f"{many['wall']:11.3f} / {many['cpu']:7.3f} s {one['wall'] / many['wall']:10.2f} "
            f"{one['cpu'] / many['cpu']:10.2f}  {one['digest'] == many['digest']}",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
