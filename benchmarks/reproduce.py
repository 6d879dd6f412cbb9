"""Time to first result: ``formation-ftc reproduce all`` with a cold and a warm compilation cache, and
the compile time of every built-in scenario as ``formation-ftc run`` compiles it.

1. ``reproduce all --profile`` in a fresh process with a fresh, empty ``FORMATION_FTC_JAX_CACHE``
   directory (cold), then again with the same directory (warm). Printed: the wall time of each
   process (interpreter start and imports included), each paper's wall time and its phase breakdown
   (compile / run / post / plot / report, see ``formation_ftc.report.profile``), and the process's CPU
   time (user + sys; on a shared machine a steadier figure than the wall time) with the load average.
2. For every built-in scenario at its default horizon: ``jax.jit(type(compiled).run).lower(params).compile()``
   (tracing, lowering and XLA compile; the persistent cache off and JAX's in-memory caches cleared
   before each scenario, so every number is a cold compile), in one fresh process: wall and process
   CPU time (XLA's compile threads included). The slowest (wall) is printed last.
3. Running a scenario again in one process (a researcher who changes a gain and re-runs): for a few
   built-in scenarios at a short horizon, ``formation_ftc.api.simulate_with_metrics`` once (traced,
   compiled, run), then again (the process's program of that structure, ``formation_ftc.sim.programs``),
   against the plain reference of a fresh ``jax.jit`` of the scenario's ``run`` per call with the
   persistent compilation cache warm (traced, lowered and loaded from the cache every time). Another gain
   is the same program (``tests/sim/test_programs.py``), so the same scenario is re-run here.

``FORMATION_FTC_XLA_OPTIONS=off`` in the environment measures XLA's default build instead of the
package's compile options (``formation_ftc.sim.runtime.xla``), for an A/B comparison.

Targets (issue "time to first result", 2 CPU cores): reproduce all cold < 90 s, warm < 40 s; compile
< 2 s per scenario. Exit status 0 always (a measurement, not a gate); ``--json FILE`` stores the numbers.

Run: ``python benchmarks/reproduce.py [--skip-reproduce] [--skip-compile] [--papers all] [--json out.json]``
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TARGET_COLD_S, TARGET_WARM_S, TARGET_COMPILE_S = 90.0, 40.0, 2.0
PHASES = ("compile", "run", "post", "plot", "report")

_COMPILE_SCRIPT = r"""
import json, sys, time
import jax
from formation_ftc.api import build_loop, list_scenarios, load_scenario
from formation_ftc.sim.runtime import xla
names = sorted(list_scenarios())
out, cpu = {}, {}
for name in names:
    jax.clear_caches()
    try:
        c = build_loop(load_scenario(name))
        t0, c0 = time.perf_counter(), time.process_time()
        xla.jit(type(c).run).lower(c).compile()  # as `formation-ftc run` compiles it (its XLA options)
        out[name] = time.perf_counter() - t0
        cpu[name] = time.process_time() - c0
    except Exception as exc:  # a scenario that cannot compile is reported, not fatal
        out[name] = f"error: {type(exc).__name__}: {exc}"
    print(json.dumps({name: out[name], "cpu:" + name: cpu.get(name, float("nan"))}), flush=True)
"""


_RERUN_SCRIPT = r"""
import json, time
import jax
from formation_ftc.api import build_loop, finish_run, load_scenario, simulate_with_metrics
from formation_ftc.sim.runtime import xla
for name in ("li2020-thm1", "yang2013-healthy", "gui2022-lof2tc", "mehrabian-isolation", "azizi2009-llfr"):
    scn = load_scenario(name)
    scn = load_scenario(name, {"simulation.horizon": 100 * scn.simulation.dt,
                               "simulation.record_every": 1})
    t = [time.perf_counter()]
    for _ in range(3):  # first run, then the same structure again (twice)
        simulate_with_metrics(scn)
        t.append(time.perf_counter())
    fresh = []
    for _ in range(2):  # the plain reference: a new jax.jit per call, persistent cache warm
        t0 = time.perf_counter()
        c = build_loop(scn)
        finish_run(scn, c, jax.block_until_ready(xla.jit(type(c).run)(c)))
        fresh.append(time.perf_counter() - t0)
    print(json.dumps({name: {"first_s": t[1] - t[0], "again_s": min(t[2] - t[1], t[3] - t[2]),
                             "fresh_jit_s": min(fresh)}}), flush=True)
"""


def _rerun_times(cache: Path) -> dict:
    return _json_lines(_RERUN_SCRIPT, str(cache))


def _has_profile() -> bool:
    """Whether this checkout's ``reproduce`` has ``--profile`` (older ones: wall times only)."""
    proc = subprocess.run(
        [sys.executable, "-m", "formation_ftc", "reproduce", "--help"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    return "--profile" in proc.stdout


def _reproduce(papers: list[str], out: Path, cache: Path) -> dict:
    env = {**os.environ, "FORMATION_FTC_JAX_CACHE": str(cache)}
    cmd = [
        sys.executable,
        "-m",
        "formation_ftc",
        "reproduce",
        *papers,
        "--out",
        str(out),
        "--force",
        "--no-3d",
        *(["--profile"] if _has_profile() else []),
    ]
    t0, r0 = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    wall, r1 = time.perf_counter() - t0, resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    if proc.returncode != 0:
        print(proc.stdout[-4000:], file=sys.stderr)
    meta = json.loads((out / "summary.json").read_text())["metadata"]
    return {
        "wall_s": wall,
        "cpu_s": cpu,
        "load_avg": os.getloadavg(),
        "exit_code": proc.returncode,
        "papers": meta["wall_time_s"],
        "profile": meta.get("profile", {}),
        "status": meta["status"],
    }


def _print_reproduce(label: str, r: dict, target: float) -> None:
    ok = "yes" if r["wall_s"] < target else "NO"
    print(
        f"\nreproduce ({label}): {r['wall_s']:.1f} s wall, {r['cpu_s']:.1f} s CPU (user + sys), exit "
        f"{r['exit_code']} (target < {target:g} s wall: {ok}; load average after: "
        + ", ".join(f"{x:.1f}" for x in r["load_avg"])
        + ")"
    )
    print(f"  {'paper':12s} {'wall':>7s} " + " ".join(f"{p:>8s}" for p in PHASES))
    for paper, wall in r["papers"].items():
        b = r["profile"].get(paper, {})
        print(
            f"  {paper:12s} {wall:7.1f} "
            + " ".join(f"{b.get(p, float('nan')):8.1f}" for p in PHASES)
            + ("" if r["status"].get(paper) == "ok" else "  FAILED")
        )


def _json_lines(script: str, cache: str) -> dict:
    """Run ``script`` in a fresh interpreter with ``FORMATION_FTC_JAX_CACHE=cache`` and merge the JSON
    objects it prints, one per line (its error output is shown when it fails)."""
    env = {**os.environ, "FORMATION_FTC_JAX_CACHE": cache}
    proc = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True)
    out: dict = {}
    for line in proc.stdout.splitlines():
        if line.startswith("{"):
            out.update(json.loads(line))
    if proc.returncode != 0:
        print(proc.stderr[-4000:], file=sys.stderr)
    return out


def _compile_times() -> dict:
    return _json_lines(_COMPILE_SCRIPT, "off")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--papers", nargs="+", default=["all"], help="papers to reproduce (default: all)"
    )
    ap.add_argument("--skip-reproduce", action="store_true", help="only the scenario compile times")
    ap.add_argument("--skip-compile", action="store_true", help="only reproduce (cold and warm)")
    ap.add_argument(
        "--skip-rerun", action="store_true", help="skip the re-run of a scenario in one process"
    )
    ap.add_argument("--json", type=Path, help="also write the numbers to this JSON file")
    ap.add_argument(
        "--keep", type=Path, help="copy the two reports (cold/, warm/) into this directory"
    )
    args = ap.parse_args(argv)
    result: dict = {"cpu_count": os.cpu_count()}
    with tempfile.TemporaryDirectory(prefix="ftc-bench-") as tmp:
        tmp_path = Path(tmp)
        if not args.skip_reproduce:
            cache = tmp_path / "jax-cache"  # fresh: created by the package on import
            result["cold"] = _reproduce(args.papers, tmp_path / "cold", cache)
            _print_reproduce("cold compilation cache", result["cold"], TARGET_COLD_S)
            result["warm"] = _reproduce(args.papers, tmp_path / "warm", cache)
            _print_reproduce("warm compilation cache", result["warm"], TARGET_WARM_S)
            if args.keep:
                for run in ("cold", "warm"):
                    shutil.copytree(tmp_path / run, args.keep / run, dirs_exist_ok=True)
        if not args.skip_rerun:
            rerun = _rerun_times(tmp_path / "rerun-cache")
            result["rerun_s"] = rerun
            print(
                "\nthe same scenario again in one process (100 steps; api.simulate_with_metrics), against a "
                "fresh jax.jit per call with a warm persistent cache"
            )
            print(
                f"  {'scenario':24s} {'first':>8s} {'again':>8s} {'fresh jit':>10s} {'ratio':>7s}"
            )
            for name, r in rerun.items():
                print(
                    f"  {name:24s} {r['first_s']:6.2f} s {r['again_s']:6.3f} s {r['fresh_jit_s']:8.3f} s "
                    f"{r['again_s'] / r['fresh_jit_s']:7.3f}"
                )
    if not args.skip_compile:
        times = _compile_times()
        result["compile_s"] = times
        print(
            f"\nformation-ftc run: compile time per built-in scenario (cold; target < {TARGET_COMPILE_S:g} s)"
        )
        cpu = {k[4:]: v for k, v in times.items() if k.startswith("cpu:")}
        times = {k: v for k, v in times.items() if not k.startswith("cpu:")}
        numeric = {k: v for k, v in times.items() if isinstance(v, float)}
        print(f"  {'scenario':36s} {'wall':>8s} {'CPU':>8s}")
        for name, t in sorted(
            times.items(),
            key=lambda kv: (isinstance(kv[1], str), kv[1] if isinstance(kv[1], float) else 0.0),
        ):
            print(
                f"  {name:36s} "
                + (
                    f"{t:6.2f} s {cpu.get(name, float('nan')):6.2f} s"
                    if isinstance(t, float)
                    else t
                )
            )
        if numeric:
            worst = max(numeric, key=numeric.__getitem__)
            ok = "yes" if numeric[worst] < TARGET_COMPILE_S else "NO"
            print(f"  slowest: {worst} {numeric[worst]:.2f} s (< {TARGET_COMPILE_S:g} s: {ok})")
    if args.json:
        args.json.write_text(json.dumps(result, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
