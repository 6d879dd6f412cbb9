"""Gui2022 metrics do not depend on the record decimation (``simulation.record_every``).

Every metric of a ``gui2022-*`` run (``gui2022-scores``) is accumulated inside the run at every step; the records are only an
output decimation. The three scenarios of the reproduction (new ILO alone, LOF2TC, COF2TC) run 4 s
(4,000 steps of 1 ms) with the x fault at 1 s and the z fault at 2 s and every metric window moved inside
(RMS from onset + 0.5 s, estimate window [0.1, 1) s, |e_z| from 2.1 s, position RMS from 1.5 s), at
``record_every = 1`` and ``= 20``; every metric must agree. The comparison is to a relative 1e-12
rather than bit for bit: the two programs scan blocks of 1 and 20 steps, which XLA may fuse
differently (the values measured here agree exactly).

The low-pass metrics (F - F_hat and, for LOF2TC, v - h averaged over consecutive boxcar blocks of
``lowpass_steps`` = 100 steps before the RMS), the chatter of F_hat about its block means and the exact
samples of ||q - q_hat|| at 0, 1 and 2 s are recomputed in numpy from the every-step records as well.
The observer's ``fault_estimate_mean`` record (the figures' record-interval mean) is not used by any
metric.

To show that the comparison can fail, windowed maxima are also recomputed in numpy: from the
every-step records they equal the in-run metrics; from the records kept every 20 steps they miss the
peaks (the sign term makes F_hat chatter with a period of 2 steps, and the records every 20 steps see
one phase of it only).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components.evaluations.gui2022_scores import lowpass_steps
from formation_ftc.papers._study import _single
from formation_ftc.papers.gui2022.figures import deputy

DT = 1e-3  # [s]
HORIZON = 4.0  # [s]
X_ONSET, Z_ONSET = 1.0, 2.0  # [s]
OVERRIDES = {
    "simulation.horizon": HORIZON,
    "actuator.onset": [X_ONSET, 0.0, Z_ONSET],
    "evaluations.0.fault_rms_delay": 0.5,
    "evaluations.0.position_rms_start": 1.5,
    "evaluations.0.estimate_start": 0.1,
    "evaluations.0.estimate_end": 1.0,
    "evaluations.0.z_amplitude_start": 2.1,
}
EXPECTED = (
    "fault_rms_err_x",
    "fault_settle_time_x",
    "fault_max_err_after_1s_x",
    "fault_max_err_after_1s_z",
    "final_fault_err_z",
    "sign_mean_vz",
    "estimate_max_err_after_start",
)
EXPECTED_LOWPASS = (
    tuple(f"fault_lowpass_rms_err_{ax}" for ax in "xyz")
    + tuple(f"fault_estimate_chatter_rms_{ax}" for ax in "xyz")
    + ("estimate_pos_err_at_0s", "estimate_pos_err_at_1s", "estimate_pos_err_at_2s")
)
EXPECTED_CONTROL = (
    "pos_rms",
    "pos_max_after_fault",
    "ex_max_fault_window",
    "ez_max_after",
    "final_pos_err",
    "final_vel_err",
)


def _blocks(values: np.ndarray, k0: int, k1: int) -> np.ndarray:
    """Samples k0 <= k < k1 of ``values`` cut into complete boxcar blocks (rows), as ``block_rms`` does."""
    box = lowpass_steps(DT)
    nb = (k1 - k0) // box
    return values[k0 : k0 + nb * box].reshape((nb, box) + values.shape[1:])


def _lowpass_rms(values: np.ndarray, k0: int, k1: int) -> float:
    return float(np.sqrt(np.mean(_blocks(values, k0, k1).mean(axis=1) ** 2)))


def _window_max(ds, values: np.ndarray, start: float, end: float) -> float:
    """max over the records with start <= t <= end (edges to 1e-9 s, as the metric windows) of ``values``."""
    t = ds.time.values
    sel = (t >= start - 1e-9) & (t <= end + 1e-9)
    return float(np.max(values[sel]))


def _deputy_run(scenario):
    """(deputy dataset, metrics) of one run, as the reproduction runs it."""
    run = _single(scenario)
    return deputy(run.dataset), run.metrics


@pytest.mark.parametrize("name", ["gui2022-ilo", "gui2022-lof2tc", "gui2022-cof2tc"])
def test_metrics_independent_of_record_every(name, same_metrics):
    out = {
        every: _deputy_run(ftc.load_scenario(name, {**OVERRIDES, "simulation.record_every": every}))
        for every in (1, 20)
    }
    (ds1, m1), (ds20, m20) = out[1], out[20]
    expected = EXPECTED + EXPECTED_LOWPASS + (EXPECTED_CONTROL if name != "gui2022-ilo" else ())
    assert set(expected) <= m1.keys()
    assert all(math.isfinite(m1[k]) for k in expected)
    same_metrics(m1, m20)

    last = HORIZON - 0.5 * DT  # the windows that end before the horizon sample
    assert ds1.time.size == round(HORIZON / DT) + 1

    # low-pass RMS, chatter and exact samples from the every-step records (numpy)
    n = round(HORIZON / DT)
    k_rms = {
        "x": round((X_ONSET + 0.5) / DT),
        "y": round(0.5 / DT),
        "z": round((Z_ONSET + 0.5) / DT),
    }
    assert lowpass_steps(DT) == 100
    for i, ax in enumerate("xyz"):
        e = ds1["fault_error"].values[:, i]
        assert _lowpass_rms(e, k_rms[ax], n) == pytest.approx(
            m1[f"fault_lowpass_rms_err_{ax}"], rel=1e-12
        ), ax
        bl = _blocks(ds1["fault_estimate"].values[:, i], round(0.5 / DT), round(X_ONSET / DT))
        chatter = float(np.sqrt(np.mean((bl - bl.mean(axis=1, keepdims=True)) ** 2)))
        assert chatter == pytest.approx(m1[f"fault_estimate_chatter_rms_{ax}"], rel=1e-9), ax
    e_pos = np.linalg.norm(ds1["estimation_error"].values[:, :3], axis=1)
    for tq in (0, 1, 2):
        assert e_pos[round(tq / DT)] == pytest.approx(m1[f"estimate_pos_err_at_{tq}s"], rel=1e-12)
    if name == "gui2022-lof2tc":
        h = ds1["synthesized_disturbance"].values
        v_h = ds1["compensation"].values - h
        k0 = round(1.5 / DT)  # position_rms_start
        for i, ax in enumerate("xyz"):
            assert _lowpass_rms(v_h[:, i], k0, n) == pytest.approx(
                m1[f"compensation_error_lowpass_rms_{ax}"], rel=1e-12
            ), ax
            assert _lowpass_rms(h[:, i], k0, n) == pytest.approx(
                m1[f"synthesized_disturbance_lowpass_rms_{ax}"], rel=1e-12
            ), ax

    def err_x(ds):  # |F_x - F_hat_x| of the deputy [m/s^2]
        return np.abs(ds["fault_error"].values[:, 0])

    # independent reductions of the every-step records equal the in-run metrics
    assert _window_max(ds1, err_x(ds1), X_ONSET + 1.0, last) == pytest.approx(
        m1["fault_max_err_after_1s_x"], rel=1e-12
    )
    assert _window_max(
        ds1, np.abs(ds1["fault_error"].values[:, 2]), Z_ONSET + 1.0, last
    ) == pytest.approx(m1["fault_max_err_after_1s_z"], rel=1e-12)
    missed = [
        _window_max(ds20, err_x(ds20), X_ONSET + 1.0, last)
        < m1["fault_max_err_after_1s_x"] * (1 - 1e-9)
    ]
    if name != "gui2022-ilo":
        e_pos = ds1["position_tracking_error"].values
        assert _window_max(ds1, e_pos, X_ONSET, last) == pytest.approx(
            m1["pos_max_after_fault"], rel=1e-12
        )
        ex1 = np.abs(ds1["tracking_error"].values[:, 0])
        assert _window_max(ds1, ex1, X_ONSET, Z_ONSET - 0.5 * DT) == pytest.approx(
            m1["ex_max_fault_window"], rel=1e-12
        )
        ex20 = np.abs(ds20["tracking_error"].values[:, 0])
        missed.append(
            _window_max(ds20, ex20, X_ONSET, Z_ONSET - 0.5 * DT)
            < m1["ex_max_fault_window"] * (1 - 1e-9)
        )
    # the records kept every 20 steps miss the peak of |F_x - F_hat_x| after the x fault (and of |e_x|)
    assert all(missed), (
        missed,
        _window_max(ds20, err_x(ds20), X_ONSET + 1.0, last),
        m1["fault_max_err_after_1s_x"],
    )
