"""Actuator ``actuator-gains``: the nominal gains before the onset and the faulty gain from it on."""

from __future__ import annotations

import jax.numpy as jnp
import pytest

from formation_ftc.api import load_scenario
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import ActuatorInputs


def test_nominal_gain_before_the_onset_faulty_from_it():
    loop = make_loop(
        load_scenario("azizi2009-flfr", {"simulation.horizon": 2.0, "actuator.onset": 1.0})
    )
    a = loop.actuator
    u = jnp.ones((4, 3))
    # b = nominal before the onset, faulty (0.8 on satellite 2, x) from it on
    for t, b2x in ((0.999, 1.0), (1.0, 0.8)):
        app = a.apply(t, u, ActuatorInputs(a.exogenous(jnp.asarray(t)), None))
        assert float(app[1, 0]) == pytest.approx(b2x) and float(app[0, 0]) == 1.0
        assert float(app[1, 1]) == 1.0
