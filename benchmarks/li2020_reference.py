"""Reference values of the li2020 report that the paper does not print, recomputed independently.

The paper shows mu1 only as curves (Figs. 6, 10, 12). The report compares our runs with a few numbers
read off a reference run of the same closed loop; this script recomputes them with the plain numpy
loop of ``benchmarks/li2020.py`` (hard-coded paper functions, Python RK4 loop, list history), which
shares no code with the package. mu1 = (1/N) sum_i ||rho_i - rho_i^d|| is evaluated at every step.

* ``tests/papers/li2020/test_reference_values.py`` recomputes the values up to t = 30 s in CI
  (about 3 x 3,000 steps);
* ``python benchmarks/li2020_reference.py --full`` recomputes every value over the 3000 s horizon
  (3 x 300,000 steps, about 10 minutes) and prints them next to the values the report uses.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from li2020 import NumpyLi2020  # noqa: E402

__all__ = ["LAWS", "reference_metrics"]

#: scenario of the report -> law of the numpy loop
LAWS = {"li2020-thm1": "thm1", "li2020-thm2-delays": "thm2", "li2020-sirftc": "sir-ftc"}
#: times at which mu1 is reported [s]
TIMES = (10.0, 20.0, 30.0, 100.0, 1000.0, 3000.0)


def reference_metrics(law: str, horizon: float, dt: float = 0.01) -> dict[str, float]:
    """mu1 at the report's times up to ``horizon`` [m], and max mu1 over [50 s, horizon] at every step."""
    ref = NumpyLi2020(law, dt=dt)
    n = round(horizon / dt)
    want = {round(t / dt): t for t in TIMES if t <= horizon + 1e-9}
    out: dict[str, float] = {}
    peak = -math.inf
    k50 = round(50.0 / dt)
    for k in range(1, n + 1):
        ref.step()
        rd, _, _ = ref._desired(k * dt)
        mu1 = float(np.mean(np.linalg.norm(ref.rho - rd, axis=1)))
        if k in want:
            out[f"mu1_at_{want[k]:g}s"] = mu1
        if k >= k50:
            peak = max(peak, mu1)
    if horizon > 50.0:
        out["mu1_max_after_50s"] = peak
    return out


def main() -> None:
    from formation_ftc.papers.li2020.reproduction import REFERENCE_RUN as USED

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--horizon", type=float, default=30.0, help="simulated time [s] (3000 for all values)"
    )
    ap.add_argument("--full", action="store_true", help="the full 3000 s horizon")
    args = ap.parse_args()
    horizon = 3000.0 if args.full else args.horizon
    for scn, law in LAWS.items():
        got = reference_metrics(law, horizon)
        for key, val in got.items():
            used = USED.get(scn, {}).get(key)
            print(
                f"{scn:20s} {key:18s} numpy {val:10.4g} m   report uses {used if used is not None else '-'}"
            )


if __name__ == "__main__":
    main()
