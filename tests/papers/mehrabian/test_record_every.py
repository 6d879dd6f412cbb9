"""Mehrabian metrics do not depend on the record decimation (``simulation.record_every``).

Every metric of a ``mehrabian`` run is accumulated inside the run at every step (the RMS and effort
integrals at every RK4 stage); the reproduction relies on this and records once per run
(``record_every = n_steps``). The three cases of the reproduction run 60 s (6,000 steps of 10 ms) with
the fault on [10, 40] s and the metric windows moved inside (fault window [10, 40] s, assessment window
[15, 40] s, whole run), at ``record_every = 1`` and ``= 20``, and through the reproduction's own batched
path (:func:`run_batch`, ``record_every = n_steps``); every metric must agree. The comparison is to a
relative 1e-12 rather than bit for bit: the programs scan blocks of 1, 20 or 6,000 steps (and the batch
is vmapped), which XLA fuses differently (measured differences are a few 1e-16).

To show that the comparison can fail, the windowed maxima are also recomputed in numpy: from the
every-step records they equal the in-run metrics; from the records kept every 20 steps (0.2 s) at
least one of them misses the peak.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.papers.mehrabian.seed_study import run_batch
from formation_ftc.papers.programs import simulate

DT = 0.01  # [s]
HORIZON = 60.0  # [s]
FAULT = (10.0, 40.0)  # [s]
ASSESS = (15.0, 40.0)  # [s]
OVERRIDES = {
    "simulation.horizon": HORIZON,
    "actuator.faults.0.start": FAULT[0],
    "actuator.faults.0.end": FAULT[1],
    "evaluations.0.fault_window": list(FAULT),
    "evaluations.0.assessment_window": list(ASSESS),
}
CASES = ["mehrabian-no-reconfig", "mehrabian-identification", "mehrabian-isolation"]
WINDOWS = {"fault_window": FAULT, "run": (0.0, HORIZON), "assessment_window": ASSESS}
AXES = ("pitch", "roll", "yaw")  # the attitude record's axis labels


def _maxima(ds) -> dict[str, float]:
    """The sampled windowed maxima recomputed in numpy from the records: samples t_k with a <= t_k < b."""
    t = ds.time.values
    sync = np.max(
        np.linalg.norm(ds["synchronisation_error"].values, axis=-1), axis=1
    )  # max over links
    track = np.max(
        np.linalg.norm(ds["tracking_error"].values, axis=-1), axis=1
    )  # max over spacecraft
    att = ds["attitude"]  # (time, spacecraft, axis)
    out = {}
    for w, (a, b) in WINDOWS.items():
        sel = (t >= a - 1e-9) & (t < b - 1e-9)
        out[f"sync_err_max_{w}"] = float(np.max(sync[sel]))
        out[f"track_err_max_{w}"] = float(np.max(track[sel]))
        for ax in AXES:
            a_ax = att.sel(axis=ax).values[sel]  # (time, spacecraft) [rad]
            out[f"spread_max_{ax}_{w}"] = float(np.max(np.ptp(a_ax, axis=1)))
            out[f"abs_max_{ax}_{w}"] = float(np.max(np.abs(a_ax)))
    return out


def test_metrics_independent_of_record_every(same_metrics):
    batched, diverged = run_batch(
        CASES, [1], OVERRIDES
    )  # the reproduction's path: one record per run
    assert np.all(diverged == -1)
    for i, name in enumerate(CASES):
        ds1, m1 = simulate(ftc.load_scenario(name, {**OVERRIDES, "simulation.record_every": 1}))
        ds20, m20 = simulate(ftc.load_scenario(name, {**OVERRIDES, "simulation.record_every": 20}))
        assert len(m1) == 36 and all(math.isfinite(v) for v in m1.values()), (
            name
        )  # 12 metrics x 3 windows
        same_metrics(m1, m20)
        same_metrics(m1, {k: float(v[i, 0]) for k, v in batched.items()})
        assert ds1.time.size == round(HORIZON / DT) + 1
        from_records = _maxima(ds1)
        assert len(from_records) == 24
        for k, v in from_records.items():
            assert v == pytest.approx(m1[k], rel=1e-12), (name, k)
        decimated = _maxima(ds20)
        assert all(decimated[k] <= m1[k] * (1 + 1e-12) for k in decimated)
        missed = [k for k in decimated if decimated[k] < m1[k] * (1 - 1e-9)]
        assert missed, name  # the records every 0.2 s miss at least one windowed peak
