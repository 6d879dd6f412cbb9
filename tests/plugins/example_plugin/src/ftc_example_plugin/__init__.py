"""Example plug-in: a smoothly saturated PD formation controller, run on the CW plant.

Adds one controller component (:class:`SmoothSaturationPd`) and one method (``example-smooth-pd``)
whose scenario file is the ``cw-formation`` one with its own ``[controller]`` section. Importing this
module registers the method; formation-ftc imports it through the ``formation_ftc.plugins`` entry point
declared in this package's ``pyproject.toml``.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import jax.numpy as jnp
from pydantic import Field

from formation_ftc.components.controllers.pd_formation import PdFormationController
from formation_ftc.config.base import StrictModel
from formation_ftc.methods.cw_formation import CwFormationScenario, make_loop
from formation_ftc.registry import Method, register_method
from formation_ftc.sim.compiled import compile_loop
from formation_ftc.sim.components import FlightInputs, as_float, component

__all__ = ["SmoothSaturationPd", "SmoothPdScenario"]


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
    max_force: float = Field(1.0, gt=0, description="Smooth per-axis force limit u_max [N].")
    desired_position: tuple[str, str, str] = Field(
        ("0", "0", "0"), description="Desired LVLH position [m]."
    )


class SmoothPdScenario(CwFormationScenario):
    smooth_pd: SmoothPdSection = SmoothPdSection()


def build(s: SmoothPdScenario):
    loop = make_loop(s)
    c = s.smooth_pd
    controller: Any = SmoothSaturationPd(
        count=s.spacecraft.count,
        kp=as_float(c.kp),
        kd=as_float(c.kd),
        mass=as_float(s.spacecraft.mass),
        max_force=as_float(c.max_force),
        desired_position=tuple(c.desired_position),
    )
    return compile_loop(dataclasses.replace(loop, controller=controller))


register_method(
    Method(
        name="example-smooth-pd",
        schema=SmoothPdScenario,
        build=build,
        description="example plug-in: smoothly saturated PD on the CW plant",
    )
)
