"""The navigation filter's consistency scores against chi-square theory: on the filter's own model
(Clohessy-Wiltshire truth, the stated sensor noise) the NEES of 6 states has mean 6 and the NIS lies
in its 95 % band 95 % of the time; a filter that understates the measurement noise tenfold is
overconfident and shows it. And the NEES of one sample against a hand computation.

The consistent filter states an acceleration noise of 1e-11 (m/s^2)^2/Hz: the truth's only unmodelled
acceleration is the LQR command's change within the 0.5 s step the filter holds it over (measured mean
NEES 7.1 at 1e-12, 5.7 at 1e-11, 5.0 at 1e-10: slightly overconfident, consistent, conservative)."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from scipy.stats import chi2

from formation_ftc import api
from formation_ftc.components.evaluations.navigation_consistency import (
    NavigationConsistency,
    chi2_band,
)
from formation_ftc.config import loader


def _run(seed: int = 0, **estimator) -> dict[str, float]:
    raw, _ = loader.read_raw("cw-lqr-navigation-filter")
    raw = copy.deepcopy(raw)
    raw["simulation"].update(horizon=600.0, seed=seed)
    raw["estimator"].update(estimator)  # the scenario scores its filter (mean_nees, *_in_band)
    _, metrics = api.simulate_with_metrics(loader.validate(raw, "navigation consistency"))
    return metrics


def test_a_consistent_filter_and_an_overconfident_one():
    """1,200 samples of 2 spacecraft per run. The NIS (white for a consistent filter) lies in its band
    within 0.02 of 0.95 in every run; the NEES is correlated in time over the filter's memory, so one
    run's mean moves with its noise seed (4.0-5.7 measured over seeds 0-3): the mean over four seeds
    lies within 30 % of 6 and each run's NEES band within 0.06 of 0.95."""
    runs = [_run(seed, acceleration_noise_psd=1e-11) for seed in range(4)]
    assert np.mean([m["mean_nees"] for m in runs]) == pytest.approx(6.0, rel=0.3)
    for m in runs:
        assert m["nees_in_band"] == pytest.approx(0.95, abs=0.06)
        assert m["nis_in_band"] == pytest.approx(0.95, abs=0.02)
    bad = _run(acceleration_noise_psd=1e-11, position_noise_std=0.01)  # sensors are 0.1 m
    assert bad["mean_nees"] > 30.0 and bad["nees_in_band"] < 0.5 and bad["nis_in_band"] < 0.5


def test_nees_of_one_sample_by_hand():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(6, 6))
    p = a @ a.T + 6 * np.eye(6)
    est, pos, vel = rng.normal(size=(2, 6)), rng.normal(size=(2, 3)), rng.normal(size=(2, 3))
    low, high = chi2_band(0.9)
    ev = NavigationConsistency(low=low, high=high)
    out = ev.outputs(
        {
            "navigation_estimate": est,
            "navigation_covariance": p,
            "navigation_nis": np.array([low - 0.1, high - 0.1]),
            "position": pos,
            "velocity": vel,
        }
    )
    e = est - np.hstack([pos, vel])
    want = [e[i] @ np.linalg.inv(p) @ e[i] for i in range(2)]
    np.testing.assert_allclose(np.asarray(out["nees"]), want, rtol=1e-12)
    assert np.asarray(out["nis_in_band"]).tolist() == [0.0, 1.0]
    assert (low, high) == pytest.approx((chi2.ppf(0.05, 6), chi2.ppf(0.95, 6)))
