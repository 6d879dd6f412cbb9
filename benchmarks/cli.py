"""Command-line start-up benchmark: wall time of the text commands ``formation-ftc --help``,
``--version``, ``list``, ``show`` and ``schema composed`` (none imports JAX: tests/test_cli_startup.py).

Each command runs as a fresh process (as a user types it), ``--repeat`` times; the median and the
maximum are printed next to the target (0.3 s, issue 37) and, for scale, the time of ``python -c pass`` (the
interpreter's own start) and of ``import jax`` (what the commands must not pay for). Exit status 1
when a median misses the target.

Run: ``python benchmarks/cli.py [--repeat 7]``
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

TARGET_S = 0.3


def _wall(argv: list[str], repeat: int) -> list[float]:
    # as installed: bytecode cached (pip compiles it at install; PYTHONDONTWRITEBYTECODE would make
    # every process compile the package's sources again), and one untimed run writes it
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    run = dict(check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    subprocess.run(argv, **run)
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        subprocess.run(argv, **run)
        times.append(time.perf_counter() - t0)
    return times


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7, help="processes per command (default 7)")
    args = ap.parse_args(argv)
    exe = shutil.which("formation-ftc") or str(Path(sys.executable).with_name("formation-ftc"))
    cases = {
        "python -c pass (interpreter start)": [sys.executable, "-c", "pass"],
        "python -c 'import jax' (for scale)": [sys.executable, "-c", "import jax"],
        "formation-ftc --help": [exe, "--help"],
        "formation-ftc --version": [exe, "--version"],
        "formation-ftc list": [exe, "list"],
        "formation-ftc show cw-pd-fault": [exe, "show", "cw-pd-fault"],
        "formation-ftc schema composed": [exe, "schema", "composed"],
        "python -m formation_ftc --help": [sys.executable, "-m", "formation_ftc", "--help"],
    }
    print(f"{'command':40s} {'median [s]':>10s} {'max [s]':>8s}  target")
    failed = False
    for label, cmd in cases.items():
        times = _wall(cmd, args.repeat)
        med = statistics.median(times)
        graded = label.startswith(("formation-ftc", "python -m"))
        ok = med < TARGET_S
        failed |= graded and not ok
        verdict = (f"< {TARGET_S} s: {'yes' if ok else 'NO'}") if graded else ""
        print(f"{label:40s} {med:10.3f} {max(times):8.3f}  {verdict}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
