"""Plant ``quaternion-rigid-body``: the derivative against the core model's eq. (4), the built plant
against its section, and what it provides to the loop."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

import formation_ftc as ftc
from formation_ftc.components.plants.quaternion_rigid_body import QuaternionRigidBodyPlant
from formation_ftc.core.dynamics.attitude_quaternion import attitude_rhs
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import TruthInputs


def test_plant_against_the_core_model():
    """With the gyroscopic term the plant is eq. (4) of the core model (no gravity gradient)."""
    J = jnp.diag(jnp.array([20.0, 25.0, 30.0]))
    w = jnp.array([[0.01, -0.02, 0.03]])
    q = jnp.array([[0.1, 0.2, -0.1, 0.9]])
    plant = QuaternionRigidBodyPlant(
        inertia=J,
        initial_body_rate=w,
        initial_quaternion=q,
        disturbance_torque=("0.1", "0", "-0.2"),
    )
    torque = jnp.array([[0.3, -0.1, 0.05]])
    d = plant.derivative(
        0.0, plant.initial_state(), TruthInputs(torque, plant.exogenous(0.0), None, None)
    )
    ref = attitude_rhs(
        0.0, jnp.concatenate([w, q], -1)[0], J, torque[0], jnp.array([0.1, 0.0, -0.2])
    )
    np.testing.assert_allclose(np.concatenate([d["omega"][0], d["q"][0]]), ref, rtol=1e-14)
    assert plant.quantity == "torque" and plant.provides() == {"quaternion-attitude-state"}


def test_built_from_its_section():
    """Initial quaternions from 3-2-1 angles (a rotation about z by 40 deg: [0, 0, sin 20, cos 20]),
    the stated body rates and the principal inertia as a diagonal matrix."""
    scn = ftc.load_scenario(
        {
            "scenario": {"name": "t", "method": "composed"},
            "simulation": {"horizon": 1.0, "dt": 0.1},
            "plant": {
                "type": "quaternion-rigid-body",
                "inertia": [20.0, 25.0, 30.0],
                "initial_attitude_deg": [[0.0, 0.0, 40.0], [0.0, 0.0, 0.0]],
                "initial_body_rate": [[0.01, 0.0, 0.0], [0.0, 0.0, -0.02]],
                "gyroscopic": False,
            },
            "controller": {"type": "attitude-pd", "K_p": 1.0, "K_d": 1.0},
        }
    )
    plant = make_loop(scn).plant
    h = np.radians(20.0)
    np.testing.assert_allclose(
        np.asarray(plant.initial_quaternion),
        [[0.0, 0.0, np.sin(h), np.cos(h)], [0.0, 0.0, 0.0, 1.0]],
        atol=1e-15,
    )
    np.testing.assert_array_equal(
        np.asarray(plant.initial_body_rate), [[0.01, 0.0, 0.0], [0.0, 0.0, -0.02]]
    )
    np.testing.assert_array_equal(np.asarray(plant.inertia), np.diag([20.0, 25.0, 30.0]))
    assert not plant.gyroscopic
