"""Start-up of the text-only commands: wall time of ``formation-ftc --help``, ``list``, ``schema composed``
and ``show cw-pd-fault``, each against ``python -c pass`` (the interpreter's own start), and whether the
command imported JAX (read from ``sys.modules`` at exit in a separate run; issue 37 item 2).

Each command runs as a fresh process ``--repeat`` times; the median, the maximum and the ratio of the
median to that of ``python -c pass`` are printed. Informative only (exit status 0); the import graph
itself is tested in ``tests/test_cli_startup.py``.

Run: ``python benchmarks/cli_startup.py [--repeat 5]``
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

COMMANDS = (["--help"], ["list"], ["schema", "composed"], ["show", "cw-pd-fault"])

_PROBE = (
    "import sys\n"
    "from formation_ftc.cli import main\n"
    "try:\n"
    "    main({argv!r})\n"
    "except SystemExit:\n"
    "    pass\n"
    "sys.stderr.write('jax imported: ' + str('jax' in sys.modules) + '\\n')\n"
)


def _wall(argv: list[str], repeat: int) -> list[float]:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        subprocess.run(argv, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        times.append(time.perf_counter() - t0)
    return times


def _imports_jax(argv: list[str]) -> str:
    out = subprocess.run(
        [sys.executable, "-c", _PROBE.format(argv=argv)], capture_output=True, text=True
    )
    line = [ln for ln in out.stderr.splitlines() if ln.startswith("jax imported: ")]
    return line[-1].removeprefix("jax imported: ") if line else "?"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="processes per command (default 5)")
    args = ap.parse_args(argv)
    exe = shutil.which("formation-ftc") or str(Path(sys.executable).with_name("formation-ftc"))
    base = statistics.median(_wall([sys.executable, "-c", "pass"], args.repeat))
    print(f"{'command':36s} {'median [s]':>10s} {'max [s]':>8s} {'x python':>9s}  jax imported")
    print(f"{'python -c pass':36s} {base:10.3f} {'':>8s} {1.0:9.1f}")
    for cmd in COMMANDS:
        times = _wall([exe, *cmd], args.repeat)
        med = statistics.median(times)
        label = "formation-ftc " + " ".join(cmd)
        print(f"{label:36s} {med:10.3f} {max(times):8.3f} {med / base:9.1f}  {_imports_jax(cmd)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
