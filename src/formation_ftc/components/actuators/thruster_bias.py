"""Actuator ``thruster-bias``: an additive, time-varying thruster fault on each axis (truth side), a
step + sinusoid + decaying term after an onset."""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np
from pydantic import Field

from formation_ftc.components._registry import BuildContext, register
from formation_ftc.components._sections import per_axis
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import Actuator, ActuatorInputs, Signal, component, static
from formation_ftc.sim.contract import VEC, as_float

__all__ = ["ThrusterBiasFaultActuator", "ThrusterBiasSection"]


@component
class ThrusterBiasFaultActuator(Actuator):
    """Applied = command + F(t), per spacecraft and axis (arrays of shape (N, 3))::

        F(t) = [t >= onset] (magnitude + amplitude sin(omega t + phase)
                             + decay_amplitude exp(-decay_rate (t - decay_origin)))

    Gui2022 Sec. 5: a step of 0.5 m/s^2 on x from 1500 s and ``0.25 sin(0.05 t + pi/4) - 0.2 e^{-0.1 t}``
    on z from 2000 s (``decay_origin`` = 0, or the onset for the shifted reading of E002-09). Onsets
    [s] are compared with the step times t_k, so an onset on the step grid acts from that step on.
    F is in the command's units (``units``: m/s^2 for acceleration commands, N for forces).
    ``per_unit_mass``: the force parts were given per unit mass and multiplied by the plant's true
    masses when built (:meth:`needs` them).
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
    per_unit_mass: bool = static(default=False)

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
        return (Signal("fault", VEC, self.units, "thruster bias fault F (true)"),)

    def outputs(self, t, command, inputs):
        return {"fault": inputs.exogenous["F"]}

    def needs(self) -> dict[str, str]:
        if not self.per_unit_mass:
            return {}
        return {"true-masses": "scale its per-unit-mass values (per_unit_mass)"}

    def provides(self) -> frozenset[str]:
        return frozenset({"thruster-bias-faults"})


class ThrusterBiasSection(StrictModel):
    """F(t) = [t >= onset] (magnitude + amplitude sin(omega t + phase) + decay_amplitude exp(-decay_rate (t - decay_origin))).
    Each field: one number, 3 values (per axis) or N x 3 values. ``per_unit_mass``: the values are
    accelerations [m/s^2] multiplied by each spacecraft's mass (the Gui2022 fault profile is written so)."""

    onset: float | list = Field(0.0, description="Onset [s].")
    magnitude: float | list = Field(0.0, description="Step part [N, or m/s^2 with per_unit_mass].")
    amplitude: float | list = Field(0.0, description="Sinusoid amplitude [N, or m/s^2].")
    omega: float | list = Field(0.0, description="Sinusoid frequency [rad/s].")
    phase: float | list = Field(0.0, description="Sinusoid phase [rad].")
    decay_amplitude: float | list = Field(0.0, description="Decaying part amplitude [N, or m/s^2].")
    decay_rate: float | list = Field(0.0, description="Decay rate [1/s].")
    decay_origin: float | list = Field(0.0, description="Origin of the decay [s].")
    per_unit_mass: bool = Field(
        False, description="Scale the force values by each spacecraft's mass."
    )


#: the profile's fields, per spacecraft and axis, and those of them that are forces (per unit mass:
#: times each spacecraft's mass)
_PROFILE = (
    "onset",
    "magnitude",
    "amplitude",
    "omega",
    "phase",
    "decay_amplitude",
    "decay_rate",
    "decay_origin",
)
_FORCES = ("magnitude", "amplitude", "decay_amplitude")


def _build(sec: ThrusterBiasSection, ctx: BuildContext) -> ThrusterBiasFaultActuator:
    """The actuator of a validated ``[actuator] type = "thruster-bias"`` section (with
    ``per_unit_mass`` and a plant without masses: unscaled, and the loop is refused by its
    :meth:`~ThrusterBiasFaultActuator.needs`)."""
    n = ctx.count
    scale = np.ones((n, 1))
    mass = getattr(ctx.plant, "mass", None)
    if sec.per_unit_mass and mass is not None:
        scale = np.asarray(mass, float)[:, None]

    def ax(name):
        v = per_axis(getattr(sec, name), n, f"actuator.{name}")
        return as_float(v * scale if name in _FORCES else v)

    return ThrusterBiasFaultActuator(
        count=n,
        **{name: ax(name) for name in _PROFILE},
        units="m s-2" if ctx.plant.quantity == "acceleration" else "N",
        per_unit_mass=sec.per_unit_mass,
    )


register(
    "actuator",
    "thruster-bias",
    ThrusterBiasSection,
    _build,
    "additive thruster fault: step + sinusoid + decaying term after an onset",
)
