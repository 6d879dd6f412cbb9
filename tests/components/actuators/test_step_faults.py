"""Actuator ``step-faults``: the step loss of effectiveness (Li2020 eq. (5)) and the additive bias
against hand-computed values; the section's ``effectiveness`` is the actuator's leaf."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from formation_ftc.components.actuators.step_faults import StepFaultActuator
from formation_ftc.config import loader
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import ActuatorInputs


def test_step_fault_actuator():
    alpha = jnp.asarray([[0.5, 1.0, 0.2]] * 2)
    onset = jnp.asarray([[1.0, 2.0, 3.0], [0.0, 5.0, 5.0]])
    act = StepFaultActuator(effectiveness=alpha, onset=onset, bias=("1", "0", "i"))
    u = jnp.ones((2, 3))
    F = act.apply(2.0, u, ActuatorInputs(act.exogenous(2.0), None))
    np.testing.assert_array_equal(np.asarray(F), [[1.5, 1.0, 2.0], [1.5, 1.0, 3.0]])


def test_onsets_snap_to_the_step_grid():
    """``onset`` is snapped to the step grid (no RK step straddles an onset); ``effectiveness`` is the
    leaf as given."""
    eff = [[0.5, 1.0, 1.0], [1.0, 0.6, 1.0], [1.0, 1.0, 0.7], [0.4, 0.4, 0.4]]
    onset = [[0.104, 0.0, 0.0], [0.0, 0.151, 0.0], [0.0, 0.0, 0.2], [0.05, 0.05, 0.05]]
    raw, _ = loader.read_raw("li2020-thm1")
    raw["simulation"] = {"horizon": 0.2, "dt": 0.01, "record_every": 5}
    raw["actuator"] = {"type": "step-faults", "effectiveness": eff, "onset": onset}
    act = make_loop(loader.validate(raw, "step")).actuator
    np.testing.assert_array_equal(act.effectiveness, eff)
    snapped = [[0.10, 0.0, 0.0], [0.0, 0.15, 0.0], [0.0, 0.0, 0.2], [0.05, 0.05, 0.05]]
    np.testing.assert_allclose(act.onset, snapped, rtol=0, atol=1e-15)
