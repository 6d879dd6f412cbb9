"""Thruster bias faults: an additive, time-varying fault on each axis (truth side)."""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp

from formation_ftc.sim.components import Actuator, ActuatorInputs, Signal, component, static

__all__ = ["ThrusterBiasFaultActuator"]


@component
class ThrusterBiasFaultActuator(Actuator):
    """Applied = command + F(t), per spacecraft and axis (arrays of shape (N, 3))::

        F(t) = [t >= onset] (magnitude + amplitude sin(omega t + phase)
                             + decay_amplitude exp(-decay_rate (t - decay_origin)))

    Gui2022 Sec. 5: a step of 0.5 m/s^2 on x from 1500 s and ``0.25 sin(0.05 t + pi/4) - 0.2 e^{-0.1 t}``
    on z from 2000 s (``decay_origin`` = 0, or the onset for the shifted reading of E002-09). Onsets
    [s] are compared with the step times t_k, so an onset on the step grid acts from that step on.
    F is in the command's units (``units``: m/s^2 for acceleration commands, N for forces).
    """

    count: int = static()
    onset: Any = 0.0  # (N, 3) [s]
    magnitude: Any = 0.0  # (N, 3) step part [command units]
    amplitude: Any = 0.0  # (N, 3) sinusoid amplitude [command units]
    omega: Any = 0.0  # (N, 3) [rad/s]
    phase: Any = 0.0  # (N, 3) [rad]
    decay_amplitude: Any = 0.0  # (N, 3) [command units]
    decay_rate: Any = 0.0  # (N, 3) [1/s]
    decay_origin: Any = 0.0  # (N, 3) [s]
    units: str = static(default="m s-2")

    def exogenous(self, t):
        f = (
            self.magnitude
            + self.amplitude * jnp.sin(self.omega * t + self.phase)
            + self.decay_amplitude * jnp.exp(-self.decay_rate * (t - self.decay_origin))
        )
        return {"F": jnp.where(t >= self.onset, f, 0.0)}

    def apply(self, t, command, inputs: ActuatorInputs):
        return command + inputs.exogenous["F"]

    def signals(self):
        return (
            Signal("fault", ("spacecraft", "axis"), self.units, "thruster bias fault F (true)"),
        )

    def outputs(self, t, command, inputs):
        return {"fault": inputs.exogenous["F"]}

    def provides(self) -> frozenset[str]:
        return frozenset({"thruster-bias-faults"})
