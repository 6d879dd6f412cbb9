"""Plant ``euler-angle-attitude``: the derivative against Euler's equation with the drawn inertia and
the held disturbance; what the plant provides to the loop."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

import formation_ftc as ftc
from formation_ftc.core.dynamics.euler_lagrange import rigid_body_rhs
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import StepContext, TruthInputs


def _loop(name="mehrabian-identification", **ov):
    return make_loop(
        ftc.load_scenario(name, {"simulation.horizon": 1.0, "simulation.record_every": 1, **ov})
    )


def test_plant_equals_the_rigid_body_model():
    """Derivative = Euler's equation with the drawn inertia J = J^ diag(1 + delta), |delta| <= 0.1, and
    the held disturbance added to the generalised torque."""
    loop = _loop()
    plant = loop.plant.prepare(loop.dt)
    J = np.asarray(plant.J)
    delta = np.diagonal(J, axis1=1, axis2=2) / np.array([20.0, 18.0, 15.0]) - 1.0
    assert np.all(np.abs(delta) <= 0.1) and np.abs(delta).max() > 0.05
    np.testing.assert_allclose(J - np.stack([np.diag(np.diagonal(j)) for j in J]), 0.0, atol=0)
    x = plant.initial_state()
    rng = np.random.default_rng(1)
    x = {"q": x["q"], "w": jnp.asarray(rng.normal(size=(8, 3)) * 0.01)}
    u = jnp.asarray(rng.normal(size=(8, 3)))
    exo = plant.held_exogenous(StepContext(jnp.asarray(25), jnp.asarray(0.25), 0.01))
    dx = plant.derivative(0.25, x, TruthInputs(u, exo, None, None))
    q_dot, w_dot = rigid_body_rhs(x["q"], x["w"], u + exo["d"], jnp.asarray(J), jnp.linalg.inv(J))
    np.testing.assert_allclose(np.asarray(dx["q"]), np.asarray(q_dot), rtol=1e-14)
    np.testing.assert_allclose(np.asarray(dx["w"]), np.asarray(w_dot), rtol=1e-12, atol=1e-18)
    # the disturbance of step 25 is a fresh N(0, 0.001) sample, different from step 26's
    d25, d26 = (
        np.asarray(plant.held_exogenous(StepContext(jnp.asarray(k), k * 0.01, 0.01))["d"])
        for k in (25, 26)
    )
    assert not np.allclose(d25, d26) and 0.005 < d25.std() < 0.08


def test_the_plant_is_driven_by_the_generalised_torque_and_measured_as_it_is():
    """The law reads the plant state and the faults are added to its input without a mapping."""
    loop = _loop()
    assert {"euler-angle-attitude-state", "euler-angle-measurement"} <= loop.plant.provides()
    assert "generalised-torque-actuation" in loop.plant.provides()
    assert type(loop.actuator).__name__ == "HeldAdditiveFaultActuator"
    np.testing.assert_array_equal(
        np.asarray(loop.plant.inertia), np.tile([20.0, 18.0, 15.0], (8, 1))
    )
