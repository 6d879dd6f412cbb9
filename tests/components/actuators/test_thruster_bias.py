"""Actuator ``thruster-bias``: the fault profile against its formula, ``per_unit_mass`` scaled by the
plant's true masses, and refused on a plant without masses."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest

from formation_ftc.components.actuators.thruster_bias import ThrusterBiasFaultActuator
from formation_ftc.config import loader
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import ActuatorInputs


def test_profile_and_per_unit_mass_scaling():
    """F(t) = [t >= onset] (magnitude + amplitude sin(omega t + phase) + decay_amplitude
    exp(-decay_rate (t - decay_origin))), force parts per unit mass times the true masses."""
    raw, _ = loader.read_raw("cw-pd-fault")
    raw["actuator"] = {
        "type": "thruster-bias",
        "onset": [1.0, 0.0, 2.0],
        "magnitude": 0.1,
        "amplitude": [0.0, 0.2, 0.0],
        "omega": 0.5,
        "phase": 0.3,
        "decay_amplitude": [0.0, 0.0, -0.05],
        "decay_rate": 0.1,
        "per_unit_mass": True,
    }
    act = make_loop(loader.validate(raw, "x")).actuator
    mass = np.array(raw["plant"]["mass"])
    t = 1.5
    f = np.asarray(act.apply(t, np.zeros((4, 3)), ActuatorInputs(act.exogenous(t), None)))
    per_kg = np.array(
        [0.1, 0.1 + 0.2 * np.sin(0.5 * t + 0.3), 0.0]  # z: before its onset (2 s)
    )
    np.testing.assert_allclose(f, mass[:, None] * per_kg[None, :], rtol=1e-14, atol=1e-15)
    assert act.signals()[0].units == "N"


def test_per_unit_mass_on_a_plant_without_masses_is_refused():
    raw, _ = loader.read_raw(
        "gui2022-ilo"
    )  # the exact CW plant of Gui2022: accelerations, no masses
    raw["actuator"]["per_unit_mass"] = True
    with pytest.raises(
        loader.ScenarioError,
        match=r"actuator thruster-bias needs the spacecraft's true masses \[kg\] .* to scale its "
        r"per-unit-mass values",
    ):
        loader.validate(raw, "gui2022-ilo")


def test_thruster_bias_profile():
    act = ThrusterBiasFaultActuator(
        count=1,
        onset=jnp.asarray([[1.0, 2.0, 3.0]]),
        magnitude=jnp.asarray([[0.5, -0.1, 0.0]]),
        amplitude=jnp.asarray([[0.0, 0.0, 0.25]]),
        omega=jnp.asarray([[0.0, 0.0, 0.05]]),
        phase=jnp.asarray([[0.0, 0.0, np.pi / 4]]),
        decay_amplitude=jnp.asarray([[0.0, 0.0, -0.2]]),
        decay_rate=jnp.asarray([[0.0, 0.0, 0.1]]),
        decay_origin=jnp.asarray([[0.0, 0.0, 3.0]]),
    )
    for t in (0.5, 1.0, 2.5, 3.0, 10.0):
        F = np.asarray(act.exogenous(jnp.asarray(t))["F"])[0]
        want = [
            0.5 * (t >= 1),
            -0.1 * (t >= 2),
            (0.25 * np.sin(0.05 * t + np.pi / 4) - 0.2 * np.exp(-0.1 * (t - 3.0))) * (t >= 3),
        ]
        np.testing.assert_allclose(F, want, rtol=1e-14, atol=1e-16)
        u = np.array([[1.0, 2.0, 3.0]])
        applied = act.apply(t, jnp.asarray(u), ActuatorInputs(act.exogenous(jnp.asarray(t)), None))
        np.testing.assert_allclose(np.asarray(applied)[0], u[0] + want, rtol=1e-14)
