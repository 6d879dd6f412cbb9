"""Evaluation ``fdi-scores`` on an intermittent fault, where the onset and the fault's first departure
from nominal differ: the detection delay is counted from the first off phase (the thruster works in the
first on phase), which the oracle reads off the recorded alarm and the fault's definition."""

from __future__ import annotations

import numpy as np

from formation_ftc.api import load_scenario, simulate_with_metrics


def test_detection_delay_of_an_intermittent_fault_counts_from_its_first_off_phase():
    onset, period, duty = 20.0, 20.0, 0.5
    first_off = onset + duty * period  # 30 s: the thruster is nominal over [20, 30)
    overrides = {
        "actuator.kind": "intermittent",
        "actuator.onset": onset,
        "actuator.period": period,
        "actuator.duty": duty,
        "simulation.record_every": 1,
        "simulation.horizon": 120.0,
    }
    ds, m = simulate_with_metrics(load_scenario("cw-fdi-identification", overrides))
    t = ds.time.values
    active = ds["fault_active"].values > 0.5
    assert not active[t < first_off].any() and active[t >= first_off].all()
    alarm = t[np.argmax(ds["fdi_detected"].values > 0.5)]
    assert alarm >= first_off  # detected once the thruster departs from nominal
    dt = float(t[1] - t[0])
    # the delay is the time from the first off phase to the alarm (the integral of fdi_pending over
    # samples: one step of rounding), not from the onset, 10 s earlier
    assert abs(m["detection_delay"] - (alarm - first_off)) <= dt + 1e-9
    assert m["correct_isolation"] == 1.0
