"""Command-line wall-time benchmark: every command as a fresh process, as a user types it.

Two tables, each with the interpreter's own start (``python -c pass``) and ``python -c "import jax"``
measured in the same run for scale:

* start-up (issue 37): ``--help``, ``--version``, ``list``, ``show``, ``schema composed`` (none imports
  JAX: tests/test_cli_startup.py); target: median < 0.3 s each;
* time to answer (issue 45): a warm ``run cw-pd-fault`` (after one untimed run that fills
  compilation caches of the benchmark's own, in a temporary directory), ``check cw-pd-fault`` and ``campaign list``; targets: ``run`` <= 2 x ``import
  jax``, ``check`` and ``campaign list`` <= 0.5 s, and the time ``run`` prints within 10 % of the wall
  time measured here for the whole process.

Each command runs ``--repeat`` times; medians and maxima are printed with the targets. Exit status 1
when a target is missed.

Run: ``python benchmarks/cli.py [--repeat 5] [--only startup|answer]``
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

STARTUP_TARGET_S = 0.3
ANSWER_TARGET_S = 0.5  # check, campaign list
RUN_OVER_JAX = 2.0  # run <= 2 x import jax
PRINTED_TOLERANCE = 0.10  # |printed - measured| <= 10 % of measured


def _env() -> dict[str, str]:
    # as installed: bytecode cached (pip compiles it at install; PYTHONDONTWRITEBYTECODE would make
    # every process compile the package's sources again)
    return {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


def _timed(argv: list[str]) -> tuple[float, str]:
    """Wall time of one process [s] and its standard output."""
    t0 = time.perf_counter()
    proc = subprocess.run(
        argv, check=True, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, env=_env()
    )
    return time.perf_counter() - t0, proc.stdout


def _wall(argv: list[str], repeat: int) -> list[float]:
    _timed(argv)  # untimed: writes the bytecode, fills the caches
    return [_timed(argv)[0] for _ in range(repeat)]


def _row(label: str, times: list[float], verdict: str = "") -> None:
    print(f"{label:44s} {statistics.median(times):10.3f} {max(times):8.3f}  {verdict}")


def _header(title: str) -> None:
    print(f"\n{title}\n{'command':44s} {'median [s]':>10s} {'max [s]':>8s}  target")


def startup(exe: str, repeat: int) -> bool:
    """The text commands (issue 37); True when every median meets its target."""
    _header(f"start-up (target: median < {STARTUP_TARGET_S} s)")
    ok_all = True
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
    for label, cmd in cases.items():
        times = _wall(cmd, repeat)
        graded = label.startswith(("formation-ftc", "python -m"))
        ok = statistics.median(times) < STARTUP_TARGET_S
        ok_all &= ok or not graded
        _row(label, times, f"< {STARTUP_TARGET_S} s: {'yes' if ok else 'NO'}" if graded else "")
    return ok_all


def answer(exe: str, repeat: int) -> bool:
    """``run``, ``check``, ``campaign list`` against ``import jax`` (issue 45); True when every target
    is met."""
    _header("time to answer (warm caches)")
    base = _wall([sys.executable, "-c", "pass"], repeat)
    _row("python -c pass (interpreter start)", base)
    jax = _wall([sys.executable, "-c", "import jax"], repeat)
    _row("python -c 'import jax'", jax)
    with tempfile.TemporaryDirectory() as tmp:
        # caches of its own, so that "warm" means the same everywhere: after one run that compiled
        # the program into them (a cache filled by an older source tree holds no usable program)
        os.environ["FORMATION_FTC_JAX_CACHE"] = str(Path(tmp) / "cache")
        run = [exe, "run", "cw-pd-fault", "--out", str(Path(tmp) / "run"), "--force", "--json"]
        _timed(run)  # untimed: compiles the program into the caches
        walls, printed = [], []
        for _ in range(repeat):
            wall, out = _timed(run)
            walls.append(wall)
            printed.append(float(json.loads(out)["wall_time"]))
    limit = RUN_OVER_JAX * statistics.median(jax)
    run_ok = statistics.median(walls) <= limit
    _row(
        "formation-ftc run cw-pd-fault",
        walls,
        f"<= {RUN_OVER_JAX:g} x import jax = {limit:.3f} s: {'yes' if run_ok else 'NO'} "
        f"({statistics.median(walls) / statistics.median(jax):.2f} x)",
    )
    errors = [abs(p - w) / w for p, w in zip(printed, walls, strict=True)]
    printed_ok = max(errors) <= PRINTED_TOLERANCE
    _row(
        "  time printed by run",
        printed,
        f"within {PRINTED_TOLERANCE:.0%} of the wall: {'yes' if printed_ok else 'NO'} "
        f"(worst {max(errors):.1%})",
    )
    ok_all = run_ok and printed_ok
    for label, cmd in {
        "formation-ftc check cw-pd-fault": [exe, "check", "cw-pd-fault"],
        "formation-ftc campaign list": [exe, "campaign", "list"],
    }.items():
        times = _wall(cmd, repeat)
        ok = statistics.median(times) <= ANSWER_TARGET_S
        ok_all &= ok
        ratio = statistics.median(times) / statistics.median(jax)
        _row(
            label,
            times,
            f"<= {ANSWER_TARGET_S} s: {'yes' if ok else 'NO'} ({ratio:.2f} x import jax)",
        )
    return ok_all


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="processes per command (default 5)")
    ap.add_argument(
        "--only", choices=("startup", "answer"), default=None, help="one table (default both)"
    )
    args = ap.parse_args(argv)
    exe = shutil.which("formation-ftc") or str(Path(sys.executable).with_name("formation-ftc"))
    ok = True
    if args.only in (None, "startup"):
        ok &= startup(exe, args.repeat)
    if args.only in (None, "answer"):
        ok &= answer(exe, args.repeat)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
