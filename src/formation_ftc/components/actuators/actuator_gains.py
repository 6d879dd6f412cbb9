"""Actuator ``actuator-gains``: true actuator gains b_i (every axis) with a step loss of effectiveness on
one axis (truth side), ``applied = b(t) * command`` (Azizi & Khorasani 2009 Sec. II, ``x'' = b u + d``).

Needs the plant's ``translational-state`` (its gains are per spacecraft and axis of the plant's
positions). The law knows only its nominal gains and the estimate ``controller.b_hat`` of the faulty
one.
"""

from __future__ import annotations

from typing import Any, Literal

import jax.numpy as jnp
import numpy as np
from pydantic import Field

from formation_ftc.components._registry import BuildContext, builder_input, per_spacecraft, register
from formation_ftc.components.sensors.chain_relative import chain_layout
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import Actuator, ActuatorInputs, Signal, component
from formation_ftc.sim.contract import VEC, as_float

__all__ = ["StepGainActuator", "ActuatorGainsSection"]

AXES = ("x", "y", "z")


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

    def needs(self) -> dict[str, str]:
        return {"translational-state": "apply its gains per spacecraft and axis"}

    def exogenous(self, t):
        return {"b": jnp.where(t >= self.onset, self.faulty_gain, self.gain)}

    def apply(self, t, command, inputs: ActuatorInputs):
        return inputs.exogenous["b"] * command  # Azizi2009 Sec. II: b_i u_i

    def signals(self):
        return (Signal("actuator_gain", VEC, "1", "true actuator gain b_i(t)"),)

    def outputs(self, t, command, inputs):
        return {"actuator_gain": inputs.exogenous["b"]}


class ActuatorGainsSection(StrictModel):
    """True actuator gains b_i (every axis) and one step loss of effectiveness (truth side):
    applied = b(t) * command (``faulty_gain`` of the component: the gains after the fault)."""

    gain: float | list[float] = Field(
        1.0, description="True actuator gains b_i before the fault [-], > 0."
    )
    spacecraft: int | None = builder_input(
        None, ge=1, description="Faulty spacecraft (1-based; none: no fault) [-]."
    )
    axis: Literal["x", "y", "z"] = builder_input("x", description="Faulty actuator axis [-].")
    effectiveness: float = builder_input(
        1.0, gt=0, le=1, description="Gain factor after the fault [-]."
    )
    onset: float = Field(0.0, ge=0, description="Fault onset, snapped to the step grid [s].")


def _build(sec: ActuatorGainsSection, ctx: BuildContext) -> StepGainActuator:
    """The actuator of a validated ``[actuator] type = "actuator-gains"`` section."""
    n = ctx.count
    _, axes = chain_layout(ctx)
    gain = per_spacecraft(sec.gain, n, "actuator.gain")
    if np.any(gain <= 0):
        raise ValueError(f"actuator.gain = {gain.tolist()}: every gain must be > 0")
    b = np.tile(gain[:, None], (1, axes))
    faulty = b.copy()
    if sec.spacecraft is not None:
        if sec.spacecraft > n:
            raise ValueError(
                f"actuator.spacecraft = {sec.spacecraft}: the plant has {n} spacecraft"
            )
        if AXES.index(sec.axis) >= axes:
            raise ValueError(f"actuator.axis = {sec.axis!r}: the plant has {axes} axes")
        faulty[sec.spacecraft - 1, AXES.index(sec.axis)] *= sec.effectiveness
    return StepGainActuator(
        gain=as_float(b),
        faulty_gain=as_float(faulty),
        onset=as_float(round(sec.onset / ctx.dt) * ctx.dt),
    )


register(
    "actuator",
    "actuator-gains",
    ActuatorGainsSection,
    _build,
    "true actuator gains with a step loss of effectiveness on one axis (applied = b(t) u)",
)
