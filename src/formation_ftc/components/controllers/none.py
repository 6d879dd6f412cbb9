"""Controller ``none``: no control (free drift), u = 0 -- a zero force, or a zero acceleration on a plant
driven by accelerations."""

from __future__ import annotations

import jax.numpy as jnp

from formation_ftc.components._registry import BuildContext, register
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import Controller, FlightInputs, component, static
from formation_ftc.sim.contract import Condition

__all__ = ["ZeroController", "FreeDrift", "NoControlSection"]


@component
class ZeroController(Controller):
    """No control (free drift): u = 0 [N]."""

    count: int = static()

    def output(self, t, state, inputs: FlightInputs):
        return jnp.zeros((self.count, 3)), None, {}

    def conditions(self, loop) -> list[Condition]:
        """On a plant with a linear model (the CW plant): the RK4 step integrates its free modes
        stably (:meth:`~formation_ftc.components.plants.clohessy_wiltshire.ClohessyWiltshirePlant.feedback_conditions`
        without a gain); on any other plant: no condition."""
        feedback_conditions = getattr(loop.plant, "feedback_conditions", None)
        return [] if feedback_conditions is None else feedback_conditions(None, loop.dt)


@component
class FreeDrift(Controller):
    """No control: u = 0 [m/s^2] (acceleration commands)."""

    quantity = "acceleration"

    count: int = static()

    def output(self, t, state, inputs: FlightInputs):
        return jnp.zeros((self.count, 3)), None, {}


class NoControlSection(StrictModel):
    """No fields: the command is zero."""


def _build(sec: NoControlSection, ctx: BuildContext) -> ZeroController | FreeDrift:
    """The controller of ``[controller] type = "none"``: zero in the quantity the plant is driven by."""
    if ctx.plant.quantity == "acceleration":  # u = 0 [m/s^2] (e.g. Gui2022's observer runs)
        return FreeDrift(count=ctx.count)
    return ZeroController(count=ctx.count)


register("controller", "none", NoControlSection, _build, "no control (free drift): u = 0")
