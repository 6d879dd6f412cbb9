"""The velocity-gain controller fault (``velocity-gain-fault``, Yang2013 Sec. 4) and its reconfiguration
by the supervisor."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

import formation_ftc as ftc
from formation_ftc import api
from formation_ftc.components.supervisors.switching import SwitchDecision
from formation_ftc.sim.components import ActuatorInputs

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


def test_velocity_gain_fault_and_its_reconfiguration():
    """The fault adds M (K2f - K2) e_V from the onset; a requested reconfiguration removes it."""
    act = _loop().actuator
    x, dec = _state_and_decision()
    X = np.asarray(x["x"])
    u = jnp.zeros((6, 6))
    e_V = X[:, 3:6]
    inp = ActuatorInputs(act.exogenous(75.0), None, dec, x)
    applied = np.asarray(act.apply(0.0, u, inp))
    expected = np.zeros((6, 6))
    expected[1, :3] = 150.0 * (-0.01 - 0.01) * e_V[1]
    np.testing.assert_allclose(applied, expected, rtol=1e-14, atol=0)
    inp = ActuatorInputs(act.exogenous(75.0), None, dec._replace(reconfigure=jnp.ones(6, bool)), x)
    assert not np.asarray(act.apply(0.0, u, inp)).any()


def test_the_fault_needs_a_law_with_a_velocity_gain():
    """A wrench law that provides no velocity gain K2 to corrupt: the loop is refused, naming the
    actuator, what it needs and who provides it."""
    import dataclasses

    import pytest

    from formation_ftc.sim.components import CompositionError

    loop = _loop()
    law = loop.controller

    class Other(type(law)):
        def provides(self):
            return frozenset()

    other = Other.__new__(Other)
    for f in dataclasses.fields(law):
        object.__setattr__(other, f.name, getattr(law, f.name))
    with pytest.raises(CompositionError) as err:
        dataclasses.replace(loop, controller=other).validate({"actuator": "velocity-gain-fault"})
    msg = str(err.value)
    assert "actuator velocity-gain-fault needs a law (12) whose velocity gain K2" in msg, msg
    assert 'controller type = "yang2013-force-torque"' in msg, msg
