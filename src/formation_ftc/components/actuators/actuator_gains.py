"""Actuator gains with a step loss of effectiveness (truth side): applied = b(t) * command."""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np

from formation_ftc.sim.components import Actuator, ActuatorInputs, Signal, component

__all__ = ["StepGainActuator"]


@component
class StepGainActuator(Actuator):
    """Applied output ``b(t) u`` per spacecraft and axis (Azizi2009 Sec. II, ``x'' = b u + d``) with
    the true actuator gains ``b(t) = gain`` before ``onset`` [s] and ``faulty_gain`` from the onset on
    (a loss of effectiveness: faulty_gain < gain on the faulty channel) [-], both (N, axes) leaves."""

    gain: Any  # (N, axes) [-]
    faulty_gain: Any  # (N, axes) [-]
    onset: Any = 0.0  # [s]

    @property
    def count(self) -> int:
        return int(np.shape(self.gain)[0])

    def exogenous(self, t):
        return {"b": jnp.where(t >= self.onset, self.faulty_gain, self.gain)}

    def apply(self, t, command, inputs: ActuatorInputs):
        return inputs.exogenous["b"] * command  # Azizi2009 Sec. II: b_i u_i

    def signals(self):
        return (Signal("actuator_gain", ("spacecraft", "axis"), "1", "true actuator gain b_i(t)"),)

    def outputs(self, t, command, inputs):
        return {"actuator_gain": inputs.exogenous["b"]}
