"""Evaluation ``li2020-formation-errors``: mu1, mu2 (literal) and mu2_vc against their formulas on the
recorded signals, the infinity-norm force metric, and the adaptive parameters' metrics of the law the
controller section declares."""

from __future__ import annotations

import numpy as np

import formation_ftc as ftc
from formation_ftc.components.evaluations.li2020_formation_errors import FormationErrors
from formation_ftc.methods.composed import make_loop


def test_formation_errors_and_inf_norm_metric_in_the_loop():
    """mu1 / mu2 / mu2_vc records equal the formulas applied to the recorded position error and
    position; max_control_force (infinity norm, every step) >= the max over the records."""
    scn = ftc.load_scenario(
        "li2020-sirftc", {"simulation.horizon": 2.0, "simulation.record_every": 10}
    )
    ds, m = ftc.api.simulate_with_metrics(scn)
    e1, rho = ds.position_error.values, ds.position.values
    np.testing.assert_allclose(
        ds.mu1.values, np.mean(np.linalg.norm(e1, axis=-1), axis=-1), rtol=1e-12
    )
    d = lambda i, j: np.linalg.norm(rho[:, i] - rho[:, j], axis=-1)  # noqa: E731
    np.testing.assert_allclose(
        ds.mu2.values, np.abs(2 * d(0, 1) - d(0, 2) - 2 * d(2, 3) + d(1, 3)), rtol=1e-9
    )
    vc = sum(
        np.linalg.norm(e1[:, i] - e1[:, j], axis=-1) for i in range(4) for j in range(i + 1, 4)
    )
    np.testing.assert_allclose(ds.mu2_vc.values, vc, rtol=1e-9)
    rec_max = float(np.max(np.abs(ds.command.values)))
    assert m["max_control_force"] >= rec_max and m["max_control_force"] < 1.2 * rec_max
    assert {s.name for s in FormationErrors().signals()} == {"mu1", "mu2", "mu2_vc"}
    assert {"b_hat_final_sc1", "b_hat_at_90pct_sc4"} <= set(m)


def test_the_adaptive_metrics_follow_the_controller():
    """The final and 0.9 T values of the law's adaptive parameters: m_hat, beta_hat, d_hat for
    li2020-adaptive, b_hat for sir-ftc (the controller section's adaptive_parameters)."""

    def adaptive(name, **ov):
        loop = make_loop(ftc.load_scenario(name, {"simulation.horizon": 1.0, **ov}))
        return sorted(
            {mt.signal for mt in loop.metrics if mt.name.endswith(("_final", "_at_90pct"))}
            & {"m_hat", "beta_hat", "d_hat", "b_hat"}
        )

    assert adaptive("li2020-thm1") == ["beta_hat", "d_hat", "m_hat"]
    assert adaptive("li2020-sirftc") == ["b_hat"]
