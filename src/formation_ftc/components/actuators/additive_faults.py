"""Additive actuator faults on windows of the step grid, sampled at the step start and held.

Mehrabian (2): the applied generalised force of spacecraft j is ``u_j + u_bar_j(t)``; every fault acts
in one channel of one spacecraft with a profile written as an expression in t [s] and i (the 1-based
spacecraft number), between a start and an end time snapped to the step grid (both inclusive). The
profile is evaluated at t_k and held over the step (truth side).
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp

from formation_ftc.core.fault_profiles import windowed_additive_faults
from formation_ftc.sim.components import Actuator, ActuatorInputs, Signal, component, static

__all__ = ["HeldAdditiveFaultActuator"]

VEC = ("spacecraft", "axis")


@component
class HeldAdditiveFaultActuator(Actuator):
    """Applied = command + u_bar(t_k) with u_bar from :func:`windowed_additive_faults` (held over the
    step). Leaves: ``windows`` (n_faults, 2) [s]. Static: fault expressions, 0-based spacecraft and
    channels, ``step`` (the step grid [s]) and ``t0``."""

    quantity = "torque"
    holds_exogenous = True

    count: int = static()
    windows: Any = None
    torques: tuple[str, ...] = static(default=())
    spacecraft: tuple[int, ...] = static(default=())
    channels: tuple[int, ...] = static(default=())
    step: float = static(default=1.0)
    t0: float = static(default=0.0)
    n_channels: int = static(default=3)

    def exogenous(self, t):
        k = jnp.round((t - self.t0) / self.step).astype(jnp.int64)
        if not self.torques:
            return {"fault": jnp.zeros((self.count, self.n_channels))}
        return {
            "fault": windowed_additive_faults(
                k,
                self.step,
                self.windows,
                self.torques,
                self.spacecraft,
                self.channels,
                self.count,
                self.n_channels,
            )
        }

    def apply(self, t, command, inputs: ActuatorInputs):
        return command + inputs.exogenous["fault"]  # (2)

    def signals(self):
        return (Signal("fault", VEC, "N m", "true additive fault u_bar (2)"),)

    def outputs(self, t, command, inputs: ActuatorInputs):
        return {"fault": inputs.exogenous["fault"]}
