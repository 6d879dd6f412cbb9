"""Sensors ``chain-relative``: the chain differences plus the noise drawn for the step, and a chain on
a plant that has no positions, or a single spacecraft, refused by validation naming both parts."""

from __future__ import annotations

import dataclasses

import jax
import numpy as np
import pytest

from formation_ftc.api import load_scenario
from formation_ftc.components.sensors.chain_relative import ChainRelativeSensors
from formation_ftc.config.loader import ScenarioError
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import CompositionError, SensorInputs


def test_chain_differences_plus_the_held_noise():
    loop = make_loop(
        load_scenario(
            "azizi2009-flfr",
            {
                "simulation.horizon": 2.0,
                "sensors.position_noise_std": 1e-3,
                "sensors.velocity_noise_std": 2e-3,
            },
        )
    )
    p, s = loop.plant, loop.sensors
    x = p.initial_state()
    key = jax.random.PRNGKey(3)
    noise = s.noise(key)
    y = s.measure(0.0, x, SensorInputs(noise, None))
    np.testing.assert_allclose(
        y["position"], np.diff(np.asarray(x["r"]), axis=0) + noise["position"], atol=1e-12
    )
    np.testing.assert_allclose(
        y["velocity"], np.diff(np.asarray(x["v"]), axis=0) + noise["velocity"], atol=1e-12
    )
    _, k_v = jax.random.split(key)
    np.testing.assert_allclose(
        noise["velocity"], 2e-3 * np.asarray(jax.random.normal(k_v, (3, 3))), rtol=1e-15
    )


def test_a_single_spacecraft_has_no_chain():
    raw = {
        "scenario": {"name": "one", "method": "composed"},
        "simulation": {"horizon": 1.0, "dt": 0.1},
        "plant": {
            "type": "clohessy-wiltshire",
            "semi_major_axis": 7000e3,
            "mass": [100.0],
            "initial_position": [[1.0, 2.0, 3.0]],
        },
        "sensors": {"type": "chain-relative"},
        "controller": {"type": "none"},
    }
    with pytest.raises(ScenarioError) as err:
        load_scenario(raw)
    msg = str(err.value)
    assert "sensors chain-relative needs two or more spacecraft" in msg, msg
    assert "a plant of two or more spacecraft" in msg, msg
    raw["plant"]["mass"] = [100.0, 100.0]
    raw["plant"]["initial_position"] = [[1.0, 2.0, 3.0], [0.0, 0.0, 0.0]]
    assert load_scenario(raw).section("sensors") is not None


def test_a_plant_without_positions_has_no_chain():
    """Chain sensors swapped into an attitude loop (quaternion plant): validation refuses them, naming
    the sensors, what they need and which plants provide it."""
    loop = make_loop(load_scenario("compose-mehrabian-on-yang2013", {"simulation.horizon": 1.0}))
    assert "translational-state" not in loop.plant.provides()
    bad = dataclasses.replace(loop, sensors=ChainRelativeSensors(count=loop.plant.count, n_axes=3))
    with pytest.raises(CompositionError) as err:
        bad.validate({"plant": "quaternion-rigid-body", "sensors": "chain-relative"})
    msg = str(err.value)
    assert "sensors chain-relative needs positions and velocities" in msg, msg
    assert 'plant type = "clohessy-wiltshire"' in msg, msg
