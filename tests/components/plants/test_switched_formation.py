"""Yang2013's switched formation (``switched-formation``): membership and the state variation (10) at
a switch, frozen inactive slots, and the attitude error dynamics (5) against numpy."""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp
import numpy as np

import formation_ftc as ftc
from formation_ftc import api
from formation_ftc.components.supervisors.switching import SwitchDecision
from formation_ftc.sim.components import TruthInputs

SHORT = {
    "simulation.horizon": 100.0,
    "supervisor.modes.1.start": 20.0,
    "supervisor.modes.2.start": 40.0,
    "supervisor.modes.3.start": 60.0,
    "supervisor.modes.4.start": 80.0,
    "actuator.faults.0.onset": 70.0,
    "simulation.record_every": 1,
}


def _loop(**ov):
    scn = ftc.load_scenario("yang2013-controller-fault", {**SHORT, **ov})
    return api.build_loop(scn)


def _state_and_decision():
    """A state of the six slots and the decision at the 4 -> 5 switch (spacecraft 6 outside)."""
    x = {
        "x": jnp.arange(6 * 13, dtype=jnp.float64).reshape(6, 13) / 100.0,
        "left_norm": jnp.zeros(6),
    }
    active = jnp.array([1.0, 1.0, 1.0, 1.0, 1.0, 0.0])
    dec = SwitchDecision(
        mode=jnp.asarray(3),
        next_mode=jnp.asarray(4),
        active=active,
        reconfigure=jnp.zeros(6, bool),
        desired_position=jnp.zeros((6, 3)),
    )
    return x, dec


def test_switched_plant_membership_and_jump():
    """S_45 placed on the slots (10), the left-limit norms kept, inactive slots frozen."""
    plant = _loop().plant
    x, dec = _state_and_decision()
    # S_45 on the slots: spacecraft 1 and 3 keep their states, 2, 4, 5 leave, 6 joins with X* = 0.2 e_1
    new = plant.jump(80.0, x, dec)
    X, Xn = np.asarray(x["x"]), np.asarray(new["x"])
    np.testing.assert_array_equal(Xn[[0, 2]], X[[0, 2]])
    assert not Xn[[1, 3, 4]].any()
    np.testing.assert_array_equal(Xn[5], np.eye(13)[0] * 0.2)
    np.testing.assert_allclose(new["left_norm"], np.linalg.norm(X, axis=1), rtol=1e-15)
    same = plant.jump(79.0, x, dec._replace(next_mode=jnp.asarray(3)))
    np.testing.assert_array_equal(np.asarray(same["x"]), X)
    # inactive slots are frozen
    u = jnp.zeros((6, 6))
    d = plant.derivative(0.0, x, TruthInputs(u, plant.exogenous(0.0), None, None, dec))
    assert not np.asarray(d["x"])[5].any() and np.asarray(d["x"])[0].any()


def test_attitude_error_rates_are_the_rigid_body_without_gyroscopic_term():
    """e_omega' = J^-1 (tau + iota), (e_q, e_q4)' = 1/2 Omega(e_omega) (e_q, e_q4) (Yang2013 (5), the
    gyroscopic term cancelled with the drift), written out in numpy."""
    plant = dataclasses.replace(_loop().plant, disturbance_torque=("0.01", "-0.02*t", "0.03*i"))
    x, _ = _state_and_decision()
    tau = np.linspace(-0.1, 0.2, 18).reshape(6, 3)
    u = jnp.concatenate([jnp.zeros((6, 3)), jnp.asarray(tau)], axis=-1)
    t = 2.0
    d = np.asarray(plant.derivative(t, x, TruthInputs(u, plant.exogenous(t), None, None))["x"])
    X, J = np.asarray(x["x"]), np.diag([25.0, 25.0, 25.0])
    for i in range(6):
        w, qv, q4 = X[i, 6:9], X[i, 9:12], X[i, 12]
        iota = np.array([0.01, -0.02 * t, 0.03 * (i + 1)])
        np.testing.assert_allclose(d[i, 6:9], np.linalg.solve(J, tau[i] + iota), rtol=1e-13)
        np.testing.assert_allclose(d[i, 9:12], 0.5 * (q4 * w + np.cross(qv, w)), rtol=1e-13)
        np.testing.assert_allclose(d[i, 12], -0.5 * w @ qv, rtol=1e-13)
