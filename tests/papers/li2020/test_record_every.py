"""Li2020 metrics do not depend on the record decimation (``simulation.record_every``).

Every metric of a ``li2020`` run is accumulated inside the run at every step; the records are only an
output decimation. Each built-in scenario of the reproduction runs 60 s (6,000 RK4 steps of 0.01 s: the
fault onsets at 10, 15 and 20 s, the ``at`` samples at 10, 20 and 30 s and the window starts at 50 s
and 54 s = 0.9 T all lie inside) at ``record_every = 1`` and ``= 20``, and every metric must agree.
The comparison is to a relative 1e-12 rather than bit for bit: the two programs scan blocks of 1 and
20 steps, which XLA may fuse differently (the values measured here agree exactly).

To show that the comparison can fail, the maximum control force and the 1 m settling time of mu1 are
also recomputed in numpy: from the every-step records they equal the in-run metrics; from the records
kept every 20 steps (0.2 s) they do not (the settling time is quantised to 0.2 s and the peak force
falls between two records).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import formation_ftc  # noqa: F401  (x64)
from formation_ftc.papers.li2020.reproduction import load_li2020, simulate_li2020

HORIZON = 60.0  # [s]
#: metrics that must be present (windowed ones included), so that an empty comparison cannot pass
EXPECTED = ("mu1_final", "mu1_max_last_10pct", "settle_time_mu1_1m", "mu1_max_after_50s", "delta_v_total",
            "max_control_force", "mu1_at_10s", "mu1_at_20s", "mu1_at_30s", "position_error_final_sc1")


def _same(m1: dict[str, float], m20: dict[str, float], rtol: float = 1e-12) -> float:
    """Assert equal metric dicts (NaN where the other is NaN); return the largest relative difference."""
    assert m1.keys() == m20.keys()
    worst = 0.0
    for k, a in m1.items():
        b = m20[k]
        if math.isnan(a):
            assert math.isnan(b), k
            continue
        assert b == pytest.approx(a, rel=rtol, abs=0.0), k
        worst = max(worst, abs(a - b) / abs(a) if a != 0 else abs(b))
    return worst


def _settle(t: np.ndarray, v: np.ndarray, threshold: float) -> float:
    """First sample time after the last sample at or above ``threshold`` (NaN if the last one is above)."""
    above = np.nonzero(v >= threshold)[0]
    if above.size == 0:
        return float(t[0])
    return float(t[above[-1] + 1]) if above[-1] + 1 < t.size else math.nan


@pytest.mark.parametrize("name", ["li2020-thm1", "li2020-thm2-delays", "li2020-sirftc"])
def test_metrics_independent_of_record_every(name):
    out = {}
    for every in (1, 20):
        ds, m = simulate_li2020(load_li2020(name, {"simulation.horizon": HORIZON, "simulation.record_every": every}))
        out[every] = (ds, m)
    (ds1, m1), (ds20, m20) = out[1], out[20]
    assert set(EXPECTED) <= m1.keys()
    assert all(math.isfinite(m1[k]) for k in EXPECTED)
    _same(m1, m20)

    # independent reductions of the records in numpy (window edges as the metrics define them)
    def force_max(ds):
        return float(np.max(np.abs(ds["command"].values)))  # max over time, spacecraft, axes of |f_i|

    def mu1_max_from(ds, start):
        t = ds.time.values
        return float(np.max(ds["mu1"].values[t >= start - 1e-9]))

    t1 = ds1.time.values
    assert t1.size == round(HORIZON / 0.01) + 1 and ds20.time.size == round(HORIZON / 0.2) + 1
    assert force_max(ds1) == pytest.approx(m1["max_control_force"], rel=1e-12)
    assert _settle(t1, ds1["mu1"].values, 1.0) == pytest.approx(m1["settle_time_mu1_1m"], rel=1e-12)
    assert mu1_max_from(ds1, 0.9 * HORIZON) == pytest.approx(m1["mu1_max_last_10pct"], rel=1e-12)
    assert mu1_max_from(ds1, 50.0) == pytest.approx(m1["mu1_max_after_50s"], rel=1e-12)
    for tq in (10.0, 20.0, 30.0):
        assert float(ds1["mu1"].values[round(tq / 0.01)]) == pytest.approx(m1[f"mu1_at_{int(tq)}s"], rel=1e-12)
    # the decimated records miss what the in-run accumulators see
    settle20 = _settle(ds20.time.values, ds20["mu1"].values, 1.0)
    missed = [force_max(ds20) < m1["max_control_force"] * (1 - 1e-9),
              abs(settle20 - m1["settle_time_mu1_1m"]) > 1e-6]
    assert all(missed), (force_max(ds20), m1["max_control_force"], settle20, m1["settle_time_mu1_1m"])
