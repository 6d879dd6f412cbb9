"""Attitude fault detection, isolation and identification from the rigid-body residual (estimator
``attitude-residual-fdi``) feeding the reconfiguration of the networked Euler-Lagrange law.

Oracles: the residual of a constant body torque on a rigid body from rest about a principal axis is the
torque itself (``J (w1 - w0) / dt`` with ``w1 = b dt / J``, no gyroscopic term); the CUSUM's detection
step in closed form for a constant standardised shift (k* = floor(h / (mu - nu)) + 1, as for the
translational residual FDI); on the attitude league's cells (exact sensing, gravity gradient, LVLH hold,
the continuous law), no alarm through a large acquisition and a correctly isolated and identified bias
that switches on the law's reconfiguration (its flag and adaptive estimate u^) only after the alarm.
"""

from __future__ import annotations

import copy
import math

import jax.numpy as jnp
import numpy as np
import pytest

from formation_ftc.api import load_scenario, simulate_with_metrics
from formation_ftc.components.estimators.attitude_residual_fdi import (
    AttitudeResidualFdi,
    rigid_body_residual,
)
from formation_ftc.league.definition import load_league
from formation_ftc.league.runner import plan_cells
from formation_ftc.sim.components import FlightInputs, StepContext

J = np.diag([20.0, 25.0, 30.0])  # kg m^2 (the attitude league's spacecraft)
DT = 0.05  # s (the league's Mehrabian step)


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_residual_of_a_body_torque_from_rest_is_the_torque(axis):
    b = 0.37  # N m about one principal axis: w(t) = b t / J_axis, w x J w = 0
    tau = np.zeros((1, 3))
    w1 = np.zeros((1, 3))
    w1[0, axis] = b * DT / J[axis, axis]
    z = np.zeros((1, 3))
    r = np.asarray(rigid_body_residual(z, z, z, w1, tau, J[None], DT))
    expected = np.zeros((1, 3))
    expected[0, axis] = b
    np.testing.assert_allclose(r, expected, rtol=1e-9, atol=1e-15)
    # the commanded torque is subtracted: commanding the same torque leaves no residual
    r0 = np.asarray(rigid_body_residual(z, z, z, w1, expected, J[None], DT))
    np.testing.assert_allclose(r0, 0.0, atol=1e-15)


def _fdi(**kw) -> AttitudeResidualFdi:
    a = dict(
        count=2,
        test="fixed",
        nominal_inertia=jnp.asarray(np.stack([J, J])),
        orbit_rate=jnp.asarray(0.0),
        torque_limit=jnp.full((2, 1), jnp.inf),
        residual_std=jnp.asarray(1e-3),
        drift=jnp.asarray(0.5),
        threshold=jnp.asarray(100.0),
        smoothing=jnp.asarray(1.0),  # identification = the last residual
        command="held",
    )
    return AttitudeResidualFdi(**{**a, **kw})


def _measure(w):
    y = {"q": jnp.zeros((2, 3)), "w": jnp.asarray(w)}
    k = jnp.asarray(0, dtype=jnp.int64)  # the residual reads the step dt from the context
    return FlightInputs(y, None, None, None, None, None, StepContext(k, 0.0 * k, DT))


def test_a_body_bias_is_isolated_and_reported_in_the_laws_channel():
    """Bias 0.2 N m about body x of spacecraft 2 at rest and aligned (q = 0): residual 0.2 N m = 200
    sigma > 100, isolated to (2, x); at q = 0 body x is the roll channel phi (index 1) of the law, and
    u* = W^T f = 0.2 N m there."""
    fdi, b = _fdi(), 0.2
    y0 = {"q": jnp.zeros((2, 3)), "w": jnp.zeros((2, 3))}
    s = fdi.initial_state(y0)
    s, est = fdi.update(0.0, s, _measure(np.zeros((2, 3))))
    assert float(est.detected) == 0.0 and float(jnp.max(est.flag)) == 0.0
    s = fdi.predict(0.0, s, jnp.zeros((2, 3)), DT)
    w1 = np.zeros((2, 3))
    w1[1, 0] = b * DT / J[0, 0]
    s, est = fdi.update(DT, s, _measure(w1))
    expected = np.zeros((2, 3))
    expected[1, 0] = b
    np.testing.assert_allclose(np.asarray(est.residual), expected, rtol=1e-9, atol=1e-15)
    assert bool(est.detected)
    np.testing.assert_array_equal(np.asarray(est.isolated), expected > 0)
    flag = np.zeros((2, 3))
    flag[1, 1] = 1.0  # body x -> phi (roll)
    np.testing.assert_array_equal(np.asarray(est.flag), flag)
    np.testing.assert_allclose(np.asarray(est.estimate), b * flag, rtol=1e-9, atol=1e-15)


def test_extrapolated_command_and_rated_torque():
    """For a law evaluated inside the step the mean command is extrapolated to the step's midpoint,
    1.5 tau_k - 0.5 tau_k-1 (the first step is not tested); a channel whose torque reaches the rated
    0.1 N m at t_k, or by the step's end (2 tau_k - tau_k-1), is not tested over the step."""
    fdi = _fdi(command="extrapolated", torque_limit=jnp.full((2, 1), 0.1))
    s = fdi.initial_state({"q": jnp.zeros((2, 3)), "w": jnp.zeros((2, 3))})
    # at q = 0 the generalised [theta, phi, psi] torque is the body torque [phi, theta, psi]
    s = fdi.predict(0.0, s, jnp.asarray([[0.02, 0.04, 0.5], [0.0, 0.0, 0.0]]), DT)
    assert not bool(s.valid)
    np.testing.assert_allclose(np.asarray(s.tau_last[0]), [0.04, 0.02, 0.5])
    s = fdi.predict(DT, s, jnp.asarray([[0.04, 0.08, 0.05], [0.0, 0.0, 0.0]]), DT)
    assert bool(s.valid)
    np.testing.assert_allclose(np.asarray(s.tau_prev[0]), [0.1, 0.05, -0.175], rtol=1e-12)
    # body x: 0.08 now, 0.12 by the step's end; y: 0.04 -> 0.06; z: 0.05 now, -0.4 by the end
    np.testing.assert_array_equal(np.asarray(s.tested), [[False, True, False], [True, True, True]])
    # an untested channel does not move the test even with a large residual
    s, est = fdi.update(2 * DT, s, _measure(np.zeros((2, 3))))
    assert not bool(est.detected) and float(jnp.abs(est.residual[0, 0])) == pytest.approx(0.1)
    assert float(est.statistic[0, 0]) == 0.0


# ------------------------------------------------------------------------- league cells (closed loop)
ONSET, HORIZON = 10.0, 12.0  # s, on the step grid
#: a large acquisition: about 2 sigma of the league's 10 deg initial dispersion per Euler angle
INITIAL_DEG = [[20.0, -15.0, 8.0], [-18.0, 4.0, 12.0], [3.0, 20.0, -17.0], [-6.0, -9.0, 21.0]]


@pytest.fixture(scope="module")
def mehrabian_cells():
    cells = plan_cells(load_league("attitude"), ["mehrabian"])["mehrabian"]
    return {(c.case, c.level): c.raw for c in cells}


def _run_cell(raw, **estimator):
    raw = copy.deepcopy(raw)
    raw["simulation"].update(horizon=HORIZON, record_every=1)
    raw["plant"]["initial_attitude_deg"] = INITIAL_DEG
    raw["actuator"]["onset"] = ONSET
    raw["estimator"].update(estimator)
    assert {"type": "fdi-scores"} in raw["evaluations"]  # the league scores its fault detectors
    raw["metrics"] = [
        dict(name="delay", signal="fdi_pending", reduce="integral", units="s"),
        dict(name="false_alarm", signal="fdi_false_alarm", reduce="max"),
        dict(name="isolated", signal="fdi_correct_isolation", reduce="last"),
    ]
    return simulate_with_metrics(load_scenario(raw))


#: the bias cell: 0.05 N m on spacecraft 2, body x, 0.1 N m limit; the CUSUM tuned for a closed form
BIAS = 0.05  # N m
MU = BIAS / 1e-3  # standardised shift of the faulty channel's residual (residual_std 1e-3 N m)
DRIFT, H = 0.25 * MU, 5.5 * MU
K_STAR = math.floor(H / (MU - DRIFT)) + 1  # 8 residual steps before the statistic exceeds h


@pytest.fixture(scope="module")
def runs(mehrabian_cells):
    """The bias and the no-fault cell at the 0.1 N m limit (one compiled program: leaves differ)."""
    bias = mehrabian_cells[("bias", "limited")]
    assert bias["actuator"]["bias"] == BIAS and bias["estimator"]["residual_std"] == 1e-3
    return {
        "bias": _run_cell(bias, drift=DRIFT, threshold=H),
        "none": _run_cell(mehrabian_cells[("none", "limited")]),
    }


def test_cusum_detects_a_bias_at_the_closed_form_step_and_reconfigures_the_law(runs):
    ds, m = runs["bias"]
    t = ds.time.values
    assert m["false_alarm"] == 0.0 and m["isolated"] == 1.0
    # the fault acts from t = ONSET; the first residual that sees it is the one at ONSET + dt
    assert m["delay"] == pytest.approx(K_STAR * DT, abs=1e-9)
    k = int(np.argmax(ds["fdi_detected"].values > 0.5))
    assert t[k] == pytest.approx(ONSET + K_STAR * DT)
    # the residual of the faulty channel after the onset is the bias, to the model's error (largest,
    # 1.5 %, where the law's command jumps inside a step: the fault's onset and the reconfiguration)
    r = ds["fdi_residual"].values[t > ONSET + 0.5 * DT, 1, 0]
    np.testing.assert_allclose(r, BIAS, rtol=0.02)
    assert np.median(r) == pytest.approx(BIAS, rel=1e-3)
    # reconfiguration: the law's flag on roll (body x at LVLH alignment) of spacecraft 2, only from the
    # alarm on; the adaptive estimate u^ moves only after it
    flag = ds["fdi_flag"].values
    assert np.all(flag[:k] == 0.0) and np.all(flag[k:, 1, 1] == 1.0)
    assert flag[k:].sum(axis=(1, 2)).max() == 1.0
    u_hat = ds["fault_estimate_adaptive"].values
    assert np.all(u_hat[: k + 1] == 0.0) and abs(u_hat[-1, 1, 1]) > 0.0
    assert np.all(u_hat[:, [0, 2, 3]] == 0.0) and np.all(u_hat[:, 1, [0, 2]] == 0.0)
    # identification: u* on the flagged channel follows the moving average (2 s) of the residual
    u_star = ds["fdi_estimate"].values[-1, 1, 1]
    assert u_star == pytest.approx(BIAS * (1.0 - math.exp(-(t[-1] - ONSET) / 2.0)), rel=0.05)


def test_no_false_alarm_through_the_acquisition(runs):
    """The league's senses are exact: on the tested channels (torque below the rated 0.1 N m) the
    residual's model error (discretisation, the law's variation inside the step) stays below the
    CUSUM's drift, so the statistic never leaves 0; the saturated channels are not tested."""
    ds, m = runs["none"]
    assert m["false_alarm"] == 0.0
    assert np.max(ds["fdi_detected"].values) == 0.0
    assert np.max(ds["fdi_statistic"].values) == 0.0
    assert np.max(np.abs(ds["fdi_residual"].values)) > 0.1  # the limit cut the acquisition's torque
    assert np.all(ds["fault_estimate_adaptive"].values == 0.0)


def test_compositions_are_checked(mehrabian_cells):
    raw = copy.deepcopy(mehrabian_cells[("none", "unsaturated")])
    raw["sensors"] = None
    del raw["sensors"]
    with pytest.raises(
        ValueError,
        match="estimator attitude-residual-fdi needs 3-2-1 Euler angles and body rates as the "
        "measurement",
    ):
        load_scenario(raw)
    raw = copy.deepcopy(mehrabian_cells[("none", "unsaturated")])
    raw["actuator"] = {"type": "euler-torque-allocation"}  # the cell keeps its fdi-scores
    with pytest.raises(
        ValueError, match=r"fdi-scores needs the true fault of one actuator channel"
    ):
        load_scenario(raw)


@pytest.mark.parametrize(("command", "holds"), [("extrapolated", True), ("held", False)])
def test_check_states_the_command_model_against_the_law_s_sampling(mehrabian_cells, command, holds):
    """``check`` states the condition registered for the type: the continuous law's command is
    modelled by the extrapolation, not by holding it."""
    from formation_ftc.api import check

    raw = copy.deepcopy(mehrabian_cells[("none", "unsaturated")])
    raw["estimator"]["command"] = command
    conds = {c.name: c for c in check(load_scenario(raw))}
    cond = conds["attitude FDI: command model over each step"]
    assert cond.holds is holds and not cond.required
    assert "controller networked-el-hinf is evaluated inside the step" in cond.value


# ------------------------------------------------------------------- identification (RLS, excitation)
def test_identification_equals_the_batch_least_squares_and_an_unexcited_channel_is_not_identified():
    """Without forgetting or random walk, recursive least squares is the regularised batch least
    squares ``theta = (P0^-1 + Phi' Phi / s^2)^-1 Phi' r / s^2`` (prior 0 +- P0). Spacecraft 1 body x
    turns about its principal axis (no gyroscopic term): a held, varying torque with a residual
    ``(e - 1) tau + b``; its y and z axes are never commanded, so their effectiveness stays unknown
    (NaN recorded, the prior's standard deviation), as for spacecraft 2."""
    e_true, b_true, sigma, prior_b = 0.6, 2e-3, 1e-4, 0.01
    fdi = _fdi(
        identification="rls",
        forgetting=jnp.asarray(1.0),
        identification_noise=jnp.asarray(sigma),
        bias_prior_std=jnp.asarray(prior_b),
        walk=jnp.zeros((2, 2)),
        effectiveness_alarm=jnp.asarray(math.inf),
    )
    rng = np.random.default_rng(5)
    taus = 0.02 * rng.standard_normal(12)
    s = fdi.initial_state({"q": jnp.zeros((2, 3)), "w": jnp.zeros((2, 3))})
    w = np.zeros((2, 3))
    for k, tau in enumerate(taus):
        command = np.zeros((2, 3))
        command[0, 1] = tau  # generalised phi = body x at q = 0
        s = fdi.predict(k * DT, s, jnp.asarray(command), DT)
        w = w.copy()
        w[0, 0] += DT * (tau + (e_true - 1.0) * tau + b_true) / J[0, 0]  # applied = e tau + b
        s, est = fdi.update((k + 1) * DT, s, _measure(w))
    out = fdi.outputs(0.0, s, est)
    phi = np.stack([taus, np.ones_like(taus)], axis=1)
    r = (e_true - 1.0) * taus + b_true
    p0_inv = np.diag([1.0, prior_b**-2])
    batch = np.linalg.solve(p0_inv + phi.T @ phi / sigma**2, phi.T @ r / sigma**2)
    np.testing.assert_allclose(np.asarray(s.theta[0, 0]), batch, rtol=1e-9)
    cov = np.linalg.inv(p0_inv + phi.T @ phi / sigma**2)
    np.testing.assert_allclose(np.asarray(s.theta_cov[0, 0]), cov, rtol=1e-6, atol=1e-18)
    assert float(out["fdi_effectiveness"][0, 0]) == pytest.approx(e_true, abs=1e-3)
    unexcited = np.asarray(out["fdi_effectiveness"])
    assert np.isnan(unexcited[0, 1:]).all() and np.isnan(unexcited[1]).all()
    np.testing.assert_allclose(np.asarray(out["fdi_effectiveness_std"])[1], 1.0)
    assert "fault-identification" in fdi.provides()


HOLD_ONSET = 90.0  # s: after the acquisition, on the settled hold (the league's onsets: 100-150 s)


@pytest.fixture(scope="module")
def active_runs():
    """The mehrabian-active method's loss-of-effectiveness and no-fault cells (one program)."""
    cells = plan_cells(load_league("attitude"), ["mehrabian-active"])["mehrabian-active"]
    raw = {(c.case, c.level): c.raw for c in cells}
    out = {}
    for case in ("loe-50", "none"):
        r = copy.deepcopy(raw[(case, "unsaturated")])
        r["simulation"].update(horizon=HOLD_ONSET + 40.0, record_every=20)
        r["plant"]["initial_attitude_deg"] = INITIAL_DEG
        r["actuator"]["onset"] = HOLD_ONSET
        r["metrics"] = [
            dict(name="false_alarm", signal="fdi_false_alarm", reduce="max"),
            dict(name="isolated", signal="fdi_correct_isolation", reduce="last"),
            dict(name="alarm", signal="fdi_detected", reduce="first", threshold=0.5, units="s"),
        ]
        out[case] = simulate_with_metrics(load_scenario(r))
    return out


def test_a_loss_of_effectiveness_on_the_hold_is_identified_and_raises_the_alarm(active_runs):
    """With the stated 1e-4 N m excitation a 50 % loss of a settled wheel, below the CUSUM's drift, is
    identified (within 10 % of 0.5, as the league's identification-scores count it) and alarms,
    isolating spacecraft 2 body x within seconds of the onset; the no-fault cell, through the same
    large acquisition, raises no alarm."""
    ds, m = active_runs["loe-50"]
    assert m["false_alarm"] == 0.0 and m["isolated"] == 1.0
    assert HOLD_ONSET < m["alarm"] < HOLD_ONSET + 10.0
    assert np.max(ds["fdi_statistic"].values[:, 1, 0]) < 20.0  # not the CUSUM: the identification
    assert float(ds["fdi_effectiveness"].values[-1, 1, 0]) == pytest.approx(0.5, rel=0.1)
    ds0, m0 = active_runs["none"]
    assert m0["false_alarm"] == 0.0 and np.max(ds0["fdi_detected"].values) == 0.0
    eff = ds0["fdi_effectiveness"].values[-1]
    assert np.all(np.abs(eff - 1.0) < 0.1)  # every channel identified, healthy
