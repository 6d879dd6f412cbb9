"""Controller ``pd``: PD formation keeping with feed-forward on the measured relative states, tracking
a desired LVLH position written as expressions."""

from __future__ import annotations

from typing import Any, Literal

import jax.numpy as jnp
import numpy as np
from pydantic import Field

from formation_ftc.components._flight_defaults import NOMINAL_MASS
from formation_ftc.components._registry import BuildContext, builder_input, per_spacecraft, register
from formation_ftc.components._sections import Vec3Expr, section_floats
from formation_ftc.components.controllers._desired_position import DesiredPositionLaw
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import FlightInputs, component
from formation_ftc.sim.contract import Condition, as_float

__all__ = ["PdFormationController", "PdSection"]


@component
class PdFormationController(DesiredPositionLaw):
    """PD formation keeping with feed-forward on measured relative states [N]::

        u_i = -kp (p_i - p_i^d(t)) - kd (v_i - v_i^d(t)) + m_i a_i^d(t)

    ``p^d(t)``, v^d and a^d as in
    :class:`~formation_ftc.components.controllers._desired_position.DesiredPositionLaw`.
    ``nominal_mass`` (N,) is the on-board mass m_i the feed-forward uses [kg]; ``max_force`` saturates
    each axis [N] (inf: none). ``is_sampled``: held over the step (ZOH)."""

    kp: Any = 0.0  # [N/m]
    kd: Any = 0.0  # [N s/m]
    nominal_mass: Any = 1.0  # (N,) on-board masses [kg]
    max_force: Any = float("inf")  # [N]

    def output(self, t, state, inputs: FlightInputs):
        y, d = inputs.measurement, inputs.exogenous
        u = (
            -self.kp * (y[:, :3] - d["p"])
            - self.kd * (y[:, 3:] - d["v"])
            + self.nominal_mass[:, None] * d["a"]
        )
        u = jnp.clip(u, -self.max_force, self.max_force)
        return u, None, {}

    def conditions(self, loop) -> list[Condition]:
        """On a plant with a linear model (``feedback_conditions``: the CW plant), the linear closed
        loop of ``u_i = -[kp I, kd I] q_i`` is stable and its RK4 step integrates every mode stably
        (:meth:`~formation_ftc.components.plants.clohessy_wiltshire.ClohessyWiltshirePlant.feedback_conditions`);
        on any other plant: no condition (outside the linear model)."""
        feedback_conditions = getattr(loop.plant, "feedback_conditions", None)
        if feedback_conditions is None:
            return []
        gain = np.hstack([self.kp * np.eye(3), self.kd * np.eye(3)])  # [N/m | N s/m]
        return feedback_conditions(gain, loop.dt)


class PdSection(StrictModel):
    """PD gains, the stated on-board masses of the feed-forward and the desired position."""

    kp: float = Field(ge=0, description="Position gain [N/m].")
    kd: float = Field(ge=0, description="Velocity gain [N s/m].")
    nominal_mass: float | list[float] = Field(
        NOMINAL_MASS,
        description=(
            "Mass the feed-forward uses, known on board [kg], one or per spacecraft (default 100 kg, a stated "
            "nominal value: never the plant's true masses)."
        ),
    )
    max_force: float | None = Field(None, gt=0, description="Per-axis saturation [N].")
    desired_position: Vec3Expr = Field(
        ("0", "0", "0"),
        description="Desired LVLH position p^d(t) per axis [m], expressions in t [s] and i.",
    )
    mode: Literal["continuous", "sampled"] = builder_input(
        "continuous", description="Every RK stage or held over the step."
    )


def _build(sec: PdSection, ctx: BuildContext) -> PdFormationController:
    """The controller of a validated ``[controller] type = "pd"`` section."""
    n = ctx.count
    return PdFormationController(
        count=n,
        **section_floats(sec, "kp", "kd"),
        nominal_mass=as_float(per_spacecraft(sec.nominal_mass, n, "controller.nominal_mass")),
        max_force=as_float(np.inf if sec.max_force is None else sec.max_force),
        desired_position=sec.desired_position,
        is_sampled=sec.mode == "sampled",
    )


register("controller", "pd", PdSection, _build, "PD formation keeping with feed-forward")
