"""Where the test suite's time goes: JAX compile phases against test time, per program and per file.

Runs the README's test command (``pytest -n 2 --dist worksteal``) with a cold compilation cache (a
fresh temporary directory, as on a fresh clone in CI) and a small pytest plugin that listens to JAX's
``jax.monitoring`` events in every xdist worker: tracing (``jaxpr_trace_duration``), lowering to
StableHLO (``jaxpr_to_mlir_module_duration``), XLA's compile (``backend_compile_duration``, which
includes loads from the persistent cache) and the persistent-cache loads themselves. Printed:

* the wall time of the run and the summed duration of the tests (setup + call + teardown);
* each compile phase in seconds, its count and its share of the summed test time;
* the programs (``fun_name``) that took the most XLA compile time, with their count -- ``jit(run)`` is
  a closed-loop scenario, ``jit(<lambda>)`` mostly a batched (``vmap``) program;
* the closed-loop programs (``jit(_run)``) grouped by structure, by structure whatever the number of
  steps, and by structure whatever the number of steps and the record interval: the XLA compile
  seconds beyond one program per group are what a program shared across horizons (and record
  intervals) would save in each worker;
* the test files with the most summed test time, and how much of it was compile.

What it does not see: work in subprocesses a test starts (the command-line and multi-process campaign
tests), which counts in their test time but not in the compile columns. This is the reference
measurement behind the ``make test`` row of docs/performance.md and its 3-minute target: the suite is
compile-bound, and no single test dominates.

Run: ``python benchmarks/test_suite_profile.py [--workers 2] [--top 15] [--json FILE] [pytest args]``
(extra arguments go to pytest, e.g. a test directory). Exit status: pytest's.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

PLUGIN = textwrap.dedent('''
    """Collects JAX compile-phase durations per test and per program; one JSON file per worker."""
    import collections, json, os
    import jax.monitoring

    PHASES = collections.defaultdict(lambda: [0, 0.0])
    PROGRAMS = collections.defaultdict(lambda: [0, 0.0])
    PER_TEST = collections.defaultdict(lambda: collections.defaultdict(float))
    DURATIONS = collections.defaultdict(float)
    CURRENT = ["<collection>"]

    def _listen(event, duration, **kw):
        name = event.rsplit("/", 1)[-1]
        PHASES[name][0] += 1
        PHASES[name][1] += duration
        PER_TEST[CURRENT[0]][name] += duration
        if name == "backend_compile_duration":
            PROGRAMS[kw.get("fun_name", "?")][0] += 1
            PROGRAMS[kw.get("fun_name", "?")][1] += duration

    jax.monitoring.register_event_duration_secs_listener(_listen)

    # closed-loop programs (``formation_ftc.sim.programs.jitted_run``): the structure they compile, with
    # and without their number of steps and record interval, so the report can say how much compile a
    # program shared across horizons would save
    STRUCTURE = [None]
    LOOP_COMPILES = []

    def _loop_listen(event, duration, **kw):
        if event.endswith("backend_compile_duration") and kw.get("fun_name") == "jit(_run)":
            if STRUCTURE[0] is not None:
                LOOP_COMPILES.append(STRUCTURE[0] + [duration])

    jax.monitoring.register_event_duration_secs_listener(_loop_listen)

    def pytest_configure(config):
        import dataclasses
        from formation_ftc.sim import programs
        original = programs.jitted_run

        def jitted_run(loop):
            every = loop.record_every
            keys = [repr(dataclasses.replace(loop, **kw).static_key) for kw in (
                {}, {"n_steps": every}, {"n_steps": 1, "record_every": 1, "metric_block": 0})]
            STRUCTURE[0] = keys
            return original(loop)

        programs.jitted_run = jitted_run

    def pytest_runtest_logstart(nodeid, location):
        CURRENT[0] = nodeid

    def pytest_runtest_logreport(report):
        DURATIONS[report.nodeid] += report.duration

    def pytest_sessionfinish(session):
        worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
        if worker == "main" and getattr(session.config.option, "numprocesses", None):
            return  # the xdist controller: it sees the workers' reports again and compiles nothing
        path = os.path.join(os.environ["FTC_TEST_PROFILE_DIR"], f"{worker}.json")
        with open(path, "w") as f:
            json.dump({"phases": PHASES, "programs": PROGRAMS, "per_test": PER_TEST,
                       "durations": DURATIONS, "loop_compiles": LOOP_COMPILES}, f)
''')

#: the groupings of closed-loop programs the report compares (the plugin's three keys, in order)
SHARING = ("same structure", "any number of steps", "any number of steps and record interval")

PHASE_NAMES = {
    "jaxpr_trace_duration": "trace",
    "jaxpr_to_mlir_module_duration": "lower to StableHLO",
    "backend_compile_duration": "XLA compile (cache loads included)",
    "cache_retrieval_time_sec": "  of which persistent-cache loads",
}


def _merge(out_dir: Path) -> dict:
    phases: dict = collections.defaultdict(lambda: [0, 0.0])
    programs: dict = collections.defaultdict(lambda: [0, 0.0])
    files: dict = collections.defaultdict(lambda: [0.0, 0.0, 0])  # test time, compile time, tests
    total = 0.0
    # per grouping of the closed-loop programs (exact structure; without the number of steps; without
    # it and the record interval): [programs, compile s, distinct groups, compile s beyond one per group]
    sharing = {name: [0, 0.0, 0, 0.0] for name in SHARING}
    for path in out_dir.glob("*.json"):
        data = json.loads(path.read_text())
        compiles = data.get("loop_compiles", [])
        for j, name in enumerate(SHARING):  # per worker: each worker compiles its own programs
            groups: dict = collections.defaultdict(list)
            for row in compiles:
                groups[row[j]].append(row[-1])
            sharing[name][0] += len(compiles)
            sharing[name][1] += sum(row[-1] for row in compiles)
            sharing[name][2] += len(groups)
            sharing[name][3] += sum(sum(v) - max(v) for v in groups.values())
        for k, (n, s) in data["phases"].items():
            phases[k][0] += n
            phases[k][1] += s
        for k, (n, s) in data["programs"].items():
            programs[k][0] += n
            programs[k][1] += s
        for nodeid, d in data["durations"].items():
            f = nodeid.split("::")[0]
            files[f][0] += d
            files[f][2] += 1
            total += d
        for nodeid, ev in data["per_test"].items():
            f = nodeid.split("::")[0]
            files[f][1] += sum(
                ev.get(k, 0.0)
                for k in (
                    "jaxpr_trace_duration",
                    "jaxpr_to_mlir_module_duration",
                    "backend_compile_duration",
                )
            )
    return {
        "phases": dict(phases),
        "programs": dict(programs),
        "files": dict(files),
        "test_seconds": total,
        "sharing": sharing,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--workers", type=int, default=2, help="xdist workers (README: 2)")
    ap.add_argument("--top", type=int, default=15, help="rows of the program and file tables")
    ap.add_argument("--json", type=Path, help="also write the merged numbers to this JSON file")
    args, pytest_args = ap.parse_known_args(argv)
    root = Path(__file__).resolve().parents[1]
    with tempfile.TemporaryDirectory(prefix="ftc-test-profile-") as tmp:
        tmp_path = Path(tmp)
        (tmp_path / "plugin").mkdir()
        (tmp_path / "plugin" / "_ftc_test_profile.py").write_text(PLUGIN)
        (tmp_path / "out").mkdir()
        env = dict(
            os.environ,
            FORMATION_FTC_JAX_CACHE=str(tmp_path / "jax-cache"),
            FTC_TEST_PROFILE_DIR=str(tmp_path / "out"),
            PYTHONPATH=os.pathsep.join(
                [str(tmp_path / "plugin"), os.environ.get("PYTHONPATH", "")]
            ),
        )
        cmd = [
            sys.executable,
            "-m",
            "pytest",
            "-p",
            "_ftc_test_profile",
            "-q",
            "-p",
            "no:cacheprovider",
        ]
        if args.workers > 1:
            cmd += ["-n", str(args.workers), "--dist", "worksteal"]
        cmd += pytest_args
        t0 = time.perf_counter()
        rc = subprocess.call(cmd, cwd=root, env=env)
        wall = time.perf_counter() - t0
        merged = _merge(tmp_path / "out")
    total = merged["test_seconds"]
    print(
        f"\ntest suite: {wall:.1f} s wall with {args.workers} worker(s), cold compilation cache; "
        f"summed test time {total:.1f} s (exit {rc})"
    )
    print(f"\n{'compile phase':40s} {'seconds':>9s} {'count':>7s} {'of test time':>13s}")
    compile_total = 0.0
    for key, label in PHASE_NAMES.items():
        n, s = merged["phases"].get(key, [0, 0.0])
        if not label.startswith(" "):
            compile_total += s
        print(f"{label:40s} {s:9.1f} {n:7d} {100 * s / max(total, 1e-9):12.0f}%")
    print(
        f"{'trace + lower + XLA compile':40s} {compile_total:9.1f} {'':7s} "
        f"{100 * compile_total / max(total, 1e-9):12.0f}%"
    )
    print(f"\n{'program (XLA compile)':40s} {'seconds':>9s} {'count':>7s} {'mean':>7s}")
    for name, (n, s) in sorted(merged["programs"].items(), key=lambda kv: -kv[1][1])[: args.top]:
        print(f"{name[:40]:40s} {s:9.1f} {n:7d} {s / max(n, 1):7.2f}")
    print(
        f"\n{'closed-loop programs grouped by':42s} {'compiles':>8s} {'seconds':>8s} "
        f"{'groups':>7s} {'s beyond one per group':>23s}"
    )
    for name, (n, s, g, extra) in merged["sharing"].items():
        print(f"{name:42s} {n:8d} {s:8.1f} {g:7d} {extra:23.1f}")
    print(f"\n{'test file':60s} {'tests':>6s} {'test s':>8s} {'compile s':>10s}")
    for name, (s, c, n) in sorted(merged["files"].items(), key=lambda kv: -kv[1][0])[: args.top]:
        print(f"{name[:60]:60s} {n:6d} {s:8.1f} {c:10.1f}")
    if args.json:
        args.json.write_text(
            json.dumps({"wall_s": wall, "workers": args.workers, "exit": rc, **merged}, indent=1)
        )
    return rc


if __name__ == "__main__":
    sys.exit(main())
