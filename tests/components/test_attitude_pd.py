"""Quaternion PD attitude baseline (composed type ``attitude-pd``) and Yang2013's attitude law as the
composed type ``yang2013-attitude``: the laws against numpy evaluations of their formulas, a closed
loop against an independent scipy integration, and rejection of compositions they cannot drive."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import formation_ftc as ftc
from formation_ftc.components.controllers._yang2013 import Yang2013AttitudeController
from formation_ftc.components.controllers.attitude_pd import AttitudePdController
from formation_ftc.components.controllers.yang2013_attitude_hold import Yang2013AttitudeHold
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import FlightInputs

INERTIA = [20.0, 25.0, 30.0]


def _hamilton(p, q):
    """p (x) q for vector-first quaternions, written out component by component (numpy)."""
    x1, y1, z1, w1 = p
    x2, y2, z2, w2 = q
    return np.array(
        [
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
        ]
    )


def _unit(rng, n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def _raw(controller, *, plant="attitude-truth", horizon=20.0, dt=0.05, attitude=None, **slots):
    attitude = attitude or [[10.0, -5.0, 20.0], [-30.0, 15.0, 5.0]]
    p = {"type": plant, "inertia": INERTIA, "initial_attitude_deg": attitude}
    if plant == "attitude-truth":
        p["state_frame"] = "lvlh"
    raw = {
        "scenario": {"name": "attitude-law-test", "method": "composed"},
        "simulation": {"horizon": horizon, "dt": dt, "record_every": 10},
        "plant": p,
        "controller": controller,
    }
    raw.update(slots)
    return raw


def _inputs(omega, q):
    return FlightInputs(
        measurement={"omega": jnp.asarray(omega), "q": jnp.asarray(q)},
        received=None,
        estimate=None,
        decision=None,
        exogenous=None,
        reference=None,
        step=None,
    )


def test_pd_output_equals_the_formula():
    """tau = -K_p sign(q_e4) q_e,v - K_d omega with q_e = q_d^* (x) q (numpy Hamilton product)."""
    rng = np.random.default_rng(7)
    q, qd, w = _unit(rng, 3), _unit(rng, 3), rng.normal(size=(3, 3)) * 0.1
    kp, kd = np.array([0.6, 1.0, 2.0]), np.array([5.4, 3.0, 1.0])
    law = AttitudePdController(count=3, K_p=kp, K_d=kd, desired_quaternion=qd)
    tau, _, out = law.output(jnp.asarray(0.0), None, _inputs(w, q))
    for i in range(3):
        qe = _hamilton(qd[i] * [-1, -1, -1, 1], q[i])
        np.testing.assert_allclose(np.asarray(out["attitude_error_quaternion"])[i], qe, atol=1e-15)
        s = 1.0 if qe[3] >= 0 else -1.0
        np.testing.assert_allclose(
            np.asarray(tau)[i], -kp[i] * s * qe[:3] - kd[i] * w[i], rtol=1e-13, atol=1e-15
        )
    # q and -q are the same attitude: the same torque (no unwinding)
    tau_neg, _, _ = law.output(jnp.asarray(0.0), None, _inputs(w, -q))
    np.testing.assert_allclose(np.asarray(tau_neg), np.asarray(tau), rtol=1e-13, atol=1e-15)


def test_pd_closed_loop_single_axis_against_scipy():
    """A yaw error about the principal z axis of a torque-free body (quaternion-rigid-body plant): the
    loop's angle follows J theta'' = -K_p sin(theta/2) - K_d theta', integrated independently."""
    kp, kd, J, th0 = 0.6, 5.4, INERTIA[2], np.deg2rad(40.0)
    raw = _raw(
        {"type": "attitude-pd", "K_p": kp, "K_d": kd},
        plant="quaternion-rigid-body",
        horizon=60.0,
        dt=0.01,
        attitude=[[0.0, 0.0, 40.0]],
    )
    ds = ftc.simulate(ftc.load_scenario(raw))
    q = ds["quaternion"].values[:, 0, :]
    theta = 2.0 * np.arctan2(q[:, 2], q[:, 3])
    assert np.allclose(q[:, :2], 0.0, atol=1e-12)  # stays a rotation about z
    t = ds["time"].values
    sol = solve_ivp(
        lambda _, y: [y[1], (-kp * np.sin(y[0] / 2) - kd * y[1]) / J],
        (0.0, t[-1]),
        [th0, 0.0],
        t_eval=t,
        rtol=1e-11,
        atol=1e-13,
    )
    np.testing.assert_allclose(theta, sol.y[0], atol=1e-7)
    assert abs(theta[-1]) < 0.05 * th0  # and it does converge


def test_yang2013_attitude_composed_equals_the_component():
    """The composed law is Yang2013AttitudeController on the error state (e_w, e_q, e_q4) = (omega,
    q_v, q4 - 1) (desired identity); evaluated directly on that state it gives the same torque."""
    loop = make_loop(
        ftc.load_scenario(_raw({"type": "yang2013-attitude", "inertia": list(INERTIA)}))
    )
    hold = loop.controller
    assert isinstance(hold, Yang2013AttitudeHold)
    rng = np.random.default_rng(11)
    q = _unit(rng, 2)
    q[:, 3] = np.abs(q[:, 3])
    w = rng.normal(size=(2, 3)) * 0.05
    tau, _, _ = hold.output(jnp.asarray(3.0), None, _inputs(w, q))
    paper = Yang2013AttitudeController(
        count=2, nominal_inertia=np.diag(INERTIA), K3=0.2, K4=1.0, K5=1.0, kappa=1e-3
    )
    err = np.concatenate([q[:, :3], q[:, 3:] - 1.0], axis=1)
    direct, _, _ = paper.output(jnp.asarray(3.0), None, _inputs(w, err))
    np.testing.assert_allclose(np.asarray(tau), np.asarray(direct), rtol=1e-14, atol=1e-16)
    # and against eq. (13) written out in numpy
    J = np.diag(INERTIA)
    for i in range(2):
        ew, eq, eq4 = w[i], q[i, :3], q[i, 3] - 1.0
        shaping = (1.0 * eq @ eq + 1.0 * eq4**2) / (2.0 * (ew @ ew + 1e-3))
        np.testing.assert_allclose(
            np.asarray(tau)[i], -J @ (0.2 * ew + eq + ew * shaping), rtol=1e-13
        )


def test_yang2013_attitude_holds_lvlh_on_the_truth_and_on_the_rigid_body():
    """Paper gains bring a 30 deg error to < 1e-3 rad in 120 s on both quaternion plants (the law reads the state)."""
    for plant in ("attitude-truth", "quaternion-rigid-body"):
        ds = ftc.simulate(
            ftc.load_scenario(_raw({"type": "yang2013-attitude"}, plant=plant, horizon=120.0))
        )
        q = ds["attitude_lvlh" if plant == "attitude-truth" else "quaternion"].values[-1]
        angle = 2.0 * np.arctan2(np.linalg.norm(q[:, :3], axis=1), np.abs(q[:, 3]))
        assert np.all(angle < 1e-3), (plant, angle)


@pytest.mark.parametrize(
    "law", [{"type": "attitude-pd", "K_p": 1.0, "K_d": 1.0}, {"type": "yang2013-attitude"}]
)
def test_laws_reject_sensors_that_change_the_state_and_translational_plants(law):
    with pytest.raises(
        Exception,
        match=f"controller {law['type']} reads the plant's quaternion state.*"
        "sensors quaternion-euler",
    ):
        make_loop(ftc.load_scenario(_raw(law, sensors={"type": "quaternion-euler"})))
    raw = {
        "scenario": {"name": "t", "method": "composed"},
        "simulation": {"horizon": 1.0, "dt": 0.1},
        "plant": {
            "type": "clohessy-wiltshire",
            "semi_major_axis": 7.0e6,
            "mass": [100.0],
            "initial_position": [[1.0, 0.0, 0.0]],
        },
        "controller": law,
    }
    with pytest.raises(
        Exception,
        match=f"controller {law['type']} converts a quaternion attitude, but plant "
        "clohessy-wiltshire has none",
    ):
        make_loop(ftc.load_scenario(raw))


def test_pd_rejects_non_unit_desired_and_bad_gains():
    with pytest.raises(Exception, match="norm 2, a unit quaternion"):
        ftc.load_scenario(
            _raw(
                {
                    "type": "attitude-pd",
                    "K_p": 1.0,
                    "K_d": 1.0,
                    "desired_quaternion": [0.0, 0.0, 0.0, 2.0],
                }
            )
        )
    with pytest.raises(Exception, match="every gain must be > 0"):
        make_loop(ftc.load_scenario(_raw({"type": "attitude-pd", "K_p": [1.0, -1.0], "K_d": 1.0})))
