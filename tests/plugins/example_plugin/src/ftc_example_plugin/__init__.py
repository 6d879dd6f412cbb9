"""Example plug-in: a smoothly saturated PD formation controller, run on the CW plant.

Adds one controller component (:class:`SmoothSaturationPd`) and registers it as the composed
controller type ``smooth-pd`` (``[controller] type = "smooth-pd"`` in any composed scenario driven by a
force). Importing this module registers the type; formation-ftc imports it through the
``formation_ftc.plugins`` entry point declared in this package's ``pyproject.toml``.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from pydantic import Field

from formation_ftc.components.controllers.pd import PdFormationController
from formation_ftc.config.base import StrictModel
from formation_ftc.methods.composed import BuildContext, register_component_type
from formation_ftc.sim.components import FlightInputs, as_float, component

__all__ = ["SmoothSaturationPd", "SmoothPdSection"]


@component
class SmoothSaturationPd(PdFormationController):
    """u = u_max tanh(u_pd / u_max) per axis [N]: the PD law of the base class, saturated smoothly."""

    def output(self, t, state, inputs: FlightInputs):
        u, _, out = super().output(t, state, inputs)
        u_max = self.max_force
        return u_max * jnp.tanh(u / u_max), None, out


class SmoothPdSection(StrictModel):
    kp: float = Field(2.0, ge=0, description="Position gain [N/m].")
    kd: float = Field(30.0, ge=0, description="Velocity gain [N s/m].")
    nominal_mass: float = Field(100.0, gt=0, description="Mass of the feed-forward [kg].")
    max_force: float = Field(1.0, gt=0, description="Smooth per-axis force limit u_max [N].")
    desired_position: tuple[str, str, str] = Field(
        ("0", "0", "0"), description="Desired LVLH position [m]."
    )


def build_smooth_pd(sec: SmoothPdSection, ctx: BuildContext) -> SmoothSaturationPd:
    return SmoothSaturationPd(
        count=ctx.count,
        kp=as_float(sec.kp),
        kd=as_float(sec.kd),
        nominal_mass=as_float(np.full(ctx.count, sec.nominal_mass)),
        max_force=as_float(sec.max_force),
        desired_position=tuple(sec.desired_position),
    )


register_component_type(
    "controller",
    "smooth-pd",
    SmoothPdSection,
    build_smooth_pd,
    "example plug-in: PD formation keeping with tanh saturation",
)
