"""Catalog: baseline (non-fault-tolerant) formation laws for composed scenarios.

* ``lqr``: LQR state feedback designed on the Clohessy-Wiltshire model of the section's circular orbit,
  weights by Bryson's rule (:func:`formation_ftc.design.lqr.cw_lqr`), with the feed-forward that makes
  the desired state an equilibrium of that model
  (:class:`~formation_ftc.components.controllers.lqr_formation.LqrFormationController`). No
  communication, no fault estimate: the reference point a fault-tolerant law should beat. Its knowledge
  is stated: the design orbit (``semi_major_axis``, ``mu``; default the ``[reference]`` orbit's) and the
  nominal masses (``mass``, default 100 kg), never the plant's truth.
"""

from __future__ import annotations

import math
from typing import Literal

from pydantic import Field, field_validator

from formation_ftc.config.base import ExprText, StrictModel
from formation_ftc.core.constants import MU_EARTH
from formation_ftc.methods.composed import BuildContext, per_spacecraft, register_component_type
from formation_ftc.sim.contract import as_float

Vec3 = tuple[float, float, float]
Vec3Expr = tuple[ExprText, ExprText, ExprText]

_BRYSON = ("max_position_error", "max_velocity_error", "max_acceleration")
#: the law's nominal on-board mass when a scenario states none [kg] (``controller.mass``)
NOMINAL_MASS = 100.0


class LqrSection(StrictModel):
    """LQR on the CW model: weights by Bryson's rule, Q = diag(1/e_max^2), R = diag(1/a_max^2)."""

    max_position_error: float | Vec3 = Field(
        description="Bryson's rule: largest acceptable position error [m], one number or one per LVLH axis; > 0."
    )
    max_velocity_error: float | Vec3 = Field(
        description="Bryson's rule: largest acceptable velocity error [m/s], one number or one per axis; > 0."
    )
    max_acceleration: float | Vec3 = Field(
        description="Bryson's rule: largest acceptable commanded acceleration [m/s^2], one number or one per axis; > 0."
    )
    semi_major_axis: float | None = Field(
        None,
        gt=0,
        description="Radius of the circular orbit the gain is designed on [m] (default: the [reference] "
        "orbit's semi_major_axis, known on board; required without a [reference]; never the "
        "plant's).",
    )
    mu: float | None = Field(
        None,
        gt=0,
        description="Gravitational parameter of the on-board model [m^3/s^2] "
        "(default: the [reference] orbit's, else Earth's "
        "3.986004418e14; never the plant's).",
    )
    mass: float | list[float] = Field(
        NOMINAL_MASS,
        description="Nominal on-board mass per spacecraft [kg], one or per spacecraft, > 0 (default "
        "100 kg, a stated nominal value: never the plant's true masses).",
    )
    desired_position: Vec3Expr = Field(
        ("0", "0", "0"), description="Desired LVLH position, expressions in t [s], i [m]."
    )
    mode: Literal["continuous", "sampled"] = Field(
        "continuous", description="Every RK stage or held over the step."
    )

    @field_validator(*_BRYSON)
    @classmethod
    def _positive(cls, value):
        values = value if isinstance(value, tuple) else (value,)
        if any(not (math.isfinite(v) and v > 0) for v in values):
            raise ValueError("every value must be finite and > 0")
        return value

    @field_validator("mass")
    @classmethod
    def _masses(cls, value):
        values = value if isinstance(value, list) else [value]
        if any(not (math.isfinite(m) and m > 0) for m in values):
            raise ValueError("every mass must be finite and > 0 kg")
        return value


def _from_reference(ctx: BuildContext, name: str):
    """A field of the [reference] orbit (known on board), or None; the plant's truth is never read."""
    value = getattr(ctx.section("reference"), name, None)
    return None if value is None else float(value)


def _lqr(sec: LqrSection, ctx: BuildContext):
    from formation_ftc.components.controllers.lqr_formation import LqrFormationController
    from formation_ftc.design.lqr import cw_lqr

    n_sc = ctx.count
    a = (
        sec.semi_major_axis
        if sec.semi_major_axis is not None
        else _from_reference(ctx, "semi_major_axis")
    )
    if a is None:
        raise ValueError(
            "controller.semi_major_axis: required (the loop has no [reference] orbit to take the design "
            "orbit from; the plant's orbit is truth the law does not read)"
        )
    mu = sec.mu if sec.mu is not None else _from_reference(ctx, "mu") or MU_EARTH
    n = math.sqrt(mu / a**3)  # mean motion of the circular design orbit [rad/s]
    design = cw_lqr(n, sec.max_position_error, sec.max_velocity_error, sec.max_acceleration)
    return LqrFormationController(
        count=n_sc,
        gain=as_float(design.K),
        mean_motion=as_float(n),
        mass=as_float(per_spacecraft(sec.mass, n_sc, "controller.mass")),
        desired_position=sec.desired_position,
        is_sampled=sec.mode == "sampled",
    )


register_component_type(
    "controller",
    "lqr",
    LqrSection,
    _lqr,
    "LQR baseline designed on Clohessy-Wiltshire (Bryson weights), no fault tolerance",
)
