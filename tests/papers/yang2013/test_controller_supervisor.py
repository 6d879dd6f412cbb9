"""Individual controllers (12)-(13) and the per-spacecraft switching supervisor (Yang2013 Sec. 3).

Truths: closed-form solution of the translational closed loop e'' + K2 e' + (K1+1) e = 0 (decay rate
eta/2 = K2/2, and growth eta1/2 for the faulty gain), exact cancellation of the drift (the closed loop
does not depend on Phi, Upsilon), the formulas (12)-(13) written out by hand, and the (29) decision
table of Theorem 2 (margins computed by hand).
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc  # noqa: F401  (x64)
from formation_ftc.components.controllers._yang2013 import attitude_control, translational_control
from formation_ftc.components.plants.switched_formation import input_norm
from formation_ftc.components.supervisors.switching import (
    RECONFIGURE,
    TOLERATE_BY_SWITCHING,
    SwitchingSupervisor,
    decision_events,
)
from formation_ftc.core.dynamics.attitude_quaternion import rigid_body_quaternion_rates
from formation_ftc.core.dynamics.tracking_error import translational_error_rates
from formation_ftc.core.integrators import rk4_step
from formation_ftc.sim.components import FlightInputs, StepContext

M = 150.0
J = jnp.diag(jnp.array([25.0, 25.0, 25.0]))


def closed_loop(t, x, K2, Phi, Ups):
    e_R, e_V, e_w, e_q, e_q4 = x[0:3], x[3:6], x[6:9], x[9:12], x[12]
    f = translational_control(e_R, e_V, Phi, M, 0.005, K2)
    tau = attitude_control(e_w, e_q, e_q4, Ups, J, 0.2, 1.0, 1.0, 1e-3)
    z = jnp.zeros(3)
    de_R, de_V = translational_error_rates(e_R, e_V, Phi, f, z, M, omega_body=-e_w)
    de_w, dq = rigid_body_quaternion_rates(e_w, x[9:13], Ups + tau, J, gyroscopic=False)
    return jnp.concatenate([de_R, de_V, de_w, dq])


def simulate(x0, K2, Phi, Ups, dt=0.05, n=20000):
    def body(x, k):
        x = rk4_step(closed_loop, k * dt, x, dt, K2, Phi, Ups)
        return x, x

    _, traj = jax.lax.scan(body, jnp.asarray(x0), jnp.arange(n))
    return np.asarray(traj)


def closed_form(e0, v0, K1, K2, t):
    """Solution of e'' + K2 e' + (K1+1) e = 0 (underdamped)."""
    a = K2 / 2
    wd = np.sqrt(K1 + 1 - a**2)
    return np.exp(-a * t)[:, None] * (
        e0 * np.cos(wd * t)[:, None] + (v0 + a * e0) / wd * np.sin(wd * t)[:, None]
    )


@pytest.mark.parametrize("K2", [0.01, -0.01])
def test_translational_closed_loop_matches_closed_form_rate_eta_over_2(K2):
    x0 = np.zeros(13)
    x0[0:3] = [0.5, -0.5, 0.5]
    x0[3:6] = [0.01, 0.0, -0.02]
    Phi = jnp.array([3e-3, -1e-3, 2e-3])  # arbitrary drift: cancelled exactly by (12)
    Ups = jnp.array([0.4, -0.2, 0.1])  # idem by (13)
    dt, n = 0.05, 20000  # 1000 s
    traj = simulate(x0, K2, Phi, Ups, dt, n)
    t = dt * np.arange(1, n + 1)
    truth = closed_form(x0[0:3], x0[3:6], 0.005, K2, t)
    # RK4 phase error at omega dt = 0.05 grows ~ t omega^5 dt^4 / 120 = 5e-5 rad after 1000 s: compare
    # relative to the envelope exp(-K2 t / 2) (initial amplitude 0.87)
    err = np.max(np.abs(traj[:, 0:3] - truth), axis=1) / np.exp(-K2 / 2 * t)
    assert np.max(err) < 1e-4, np.max(err)
    # decay/growth of the amplitude over 1000 s is exp(-K2/2 * 1000) (eta = 0.01 -> e^-5)
    amp = lambda k: np.sqrt(np.sum(traj[k, 0:3] ** 2) + np.sum(traj[k, 3:6] ** 2))  # noqa: E731
    ratio = np.max([amp(k) for k in range(n - 200, n)]) / np.max([amp(k) for k in range(0, 200)])
    assert ratio == pytest.approx(np.exp(-K2 / 2 * (n - 200) * dt), rel=0.05)
    # attitude error stays exactly zero without torque disturbance (E001-03)
    assert np.max(np.abs(traj[:, 6:])) == 0.0


def test_drift_cancellation_and_laws_by_hand():
    x = jnp.arange(1.0, 14.0) / 10.0
    a = closed_loop(0.0, x, 0.01, jnp.zeros(3), jnp.zeros(3))
    b = closed_loop(0.0, x, 0.01, jnp.array([1.0, 2.0, 3.0]), jnp.array([-4.0, 5.0, 0.5]))
    np.testing.assert_allclose(a, b, atol=1e-14)
    z = jnp.zeros(3)
    f = translational_control(x[0:3], x[3:6], z, M, 0.005, 0.01)
    np.testing.assert_allclose(f, M * (1.005 * x[0:3] + 0.01 * x[3:6]), rtol=1e-14)
    e_w, e_q, e_q4 = x[6:9], x[9:12], x[12]
    tau = attitude_control(e_w, e_q, e_q4, z, J, 0.2, 1.0, 1.0, 1e-3)
    shaping = (jnp.sum(e_q**2) + e_q4**2) / (2 * (jnp.sum(e_w**2) + 1e-3))
    np.testing.assert_allclose(tau, -J @ (0.2 * e_w + e_q + e_w * shaping), rtol=1e-14)
    np.testing.assert_allclose(
        input_norm(f, tau), np.sqrt(np.sum(f**2) + np.sum(tau**2)), rtol=1e-14
    )


def make_supervisor(leaves_slot1=True, delay=0):
    # modes start at 0, 1000, 2000 s (dt = 1 s); slot 1 leaves at the switch out of mode 2 (index 1)
    leaves = np.zeros((3, 3), bool)
    leaves[1, 1] = leaves_slot1
    return SwitchingSupervisor(
        count=3,
        switch_steps=jnp.array([0, 1000, 2000]),
        active=jnp.ones((3, 3)),
        leaves_at_next_switch=jnp.asarray(leaves),
        eta=0.01,
        eta1=jnp.full(3, 0.01),
        delay_bound_steps=jnp.full(3, delay),
        desired_position=((("0", "0", "0"),) * 3,) * 3,
    )


def flight(diagnosed, k):
    """Flight inputs at step k (dt = 1 s, t0 = 0: t_k = k s)."""
    k = jnp.asarray(k, dtype=jnp.int64)
    step = StepContext(k, 1.0 * k, 1.0)
    return FlightInputs(None, None, {"diagnosed": jnp.asarray(diagnosed)}, None, None, None, step)


@pytest.mark.parametrize(
    "k_diag, leaves, delay, expected, margin",
    [
        (1800, True, 0, TOLERATE_BY_SWITCHING, 3.0),  # dt1 = 800, dt2 = 200: 0.005*800 - 0.005*200
        (1500, True, 0, TOLERATE_BY_SWITCHING, 0.0),  # dt1 = dt2: boundary of (29)
        (1300, True, 0, RECONFIGURE, -2.0),  # fault too early: (29) fails
        (1800, False, 0, RECONFIGURE, 3.0),  # (29) holds, but the spacecraft stays: reconfigure
        (1850, True, 100, TOLERATE_BY_SWITCHING, 2.5),  # delay bound counted in dt2: t_f = 1750
        (2500, True, 0, RECONFIGURE, -np.inf),  # last mode: nothing to switch to
    ],
)
def test_supervisor_decision_table(k_diag, leaves, delay, expected, margin):
    sup = make_supervisor(leaves, delay)
    update = jax.jit(sup.update)
    diagnosed = [False, True, False]
    state, dec = update(float(k_diag), sup.initial_state(), flight(diagnosed, k_diag))
    assert int(state["decision"][1]) == expected
    assert float(state["margin_29"][1]) == pytest.approx(margin)
    assert bool(dec.reconfigure[1]) == (expected == RECONFIGURE)
    assert int(state["decision"][0]) == 0 and int(state["decision"][2]) == 0
    # decided once: later steps keep the decision (and its time); the decision of a step is its mode
    state2, held = update(float(k_diag + 10), state, flight(diagnosed, k_diag + 10))
    assert float(state2["decision_time"][1]) == k_diag
    assert int(held.mode) == int(np.searchsorted([0, 1000, 2000], k_diag + 10, side="right") - 1)
    out = sup.outputs(0.0, state2, held)
    ev = decision_events(
        *(
            out[name]
            for name in (
                "supervisor_decision",
                "supervisor_decision_time",
                "supervisor_decision_mode",
                "condition_29_margin",
            )
        ),
        1.0,
    )
    assert (
        len(ev) == 1
        and ev[0]["spacecraft"] == 2
        and ev[0]["time"] == k_diag
        and ev[0]["step"] == k_diag
    )


def test_supervisor_ignores_a_diagnosis_outside_the_formation_and_vmaps():
    sup = make_supervisor()
    sup = type(sup)(**{**sup.__dict__, "active": jnp.asarray([[1.0, 0.0, 1.0]] * 3)})
    state, _ = sup.update(1800.0, sup.initial_state(), flight([False, True, False], 1800))
    assert int(state["decision"][1]) == 0
    sup = make_supervisor()
    new, _ = jax.vmap(
        lambda k: sup.update(1.0 * k, sup.initial_state(), flight([False, True, False], k))
    )(jnp.array([1800, 1300]))
    assert new["decision"][:, 1].tolist() == [TOLERATE_BY_SWITCHING, RECONFIGURE]
