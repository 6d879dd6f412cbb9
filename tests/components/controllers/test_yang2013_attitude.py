"""Controller ``yang2013-attitude``: Yang2013's attitude law (13) holding a fixed attitude, against the
component on the error state and eq. (13) written out in numpy, and a closed loop on both quaternion
plants."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

import formation_ftc as ftc
from formation_ftc.components.controllers._yang2013 import Yang2013AttitudeController
from formation_ftc.components.controllers.yang2013_attitude import Yang2013AttitudeHold
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import FlightInputs

INERTIA = [20.0, 25.0, 30.0]


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


def test_yang2013_attitude_composed_equals_the_component():
    """The composed law is Yang2013AttitudeController on the error state (e_w, e_q, e_q4) = (omega,
    q_v, q4 - 1) (desired identity); evaluated directly on that state it gives the same torque."""
    loop = make_loop(
        ftc.load_scenario(_raw({"type": "yang2013-attitude", "nominal_inertia": list(INERTIA)}))
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


def test_law_13_against_the_formula_written_out():
    J = jnp.diag(jnp.array([20.0, 25.0, 30.0]))
    law = Yang2013AttitudeController(
        count=1,
        nominal_inertia=J,
        K3=jnp.asarray(0.2),
        K4=jnp.asarray(1.0),
        K5=jnp.asarray(2.0),
        kappa=jnp.asarray(1e-3),
    )
    w = jnp.array([[0.01, -0.02, 0.03]])
    q = jnp.array([[0.1, 0.2, -0.1, 0.9]])
    tau, _, _ = law.output(
        0.0, None, FlightInputs({"omega": w, "q": q}, None, None, None, None, None, None)
    )
    s = (np.sum(q[0, :3] ** 2) + 2.0 * q[0, 3] ** 2) / (2 * (np.sum(w[0] ** 2) + 1e-3))
    np.testing.assert_allclose(
        tau[0], -np.asarray(J) @ (0.2 * w[0] + q[0, :3] + w[0] * s), rtol=1e-14
    )
    assert law.quantity == "torque"
