"""Catalog: Yang2013's translational formation law (12) for translational plants, alone or relative to
the spacecraft each one references over a (delayed) network.

* ``yang2013-translational``: eq. (12) on the measured (N, 6) relative state, tracking each spacecraft's
  own desired position; exchanges no messages (a delayed network is rejected with it).
* ``yang2013-relative``: the same law wrapped in
  :class:`~formation_ftc.components.controllers.neighbour_relative.NeighbourRelativeController`: every
  spacecraft sends its formation error and spacecraft i keeps its offset relative to the (delayed)
  formation errors it receives, weighted by ``coupling`` beta_i. Needs a ``[network]``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, ClassVar

from pydantic import Field, model_validator

from formation_ftc.config.base import ExprText, StrictModel
from formation_ftc.methods.composed import BuildContext, per_spacecraft, register_component_type
from formation_ftc.sim.contract import as_float

if TYPE_CHECKING:
    from formation_ftc.components.controllers.neighbour_relative import NeighbourRelativeController
    from formation_ftc.components.controllers.yang2013_individual import (
        Yang2013TranslationalController,
    )

Vec3Expr = tuple[ExprText, ExprText, ExprText]

#: the law's nominal on-board mass when a scenario states none [kg] (``controller.nominal_mass``):
#: Yang2013's spacecraft
NOMINAL_MASS = 150.0


class Yang2013TranslationalSection(StrictModel):
    """Yang2013 eq. (12): f_i = M_i (a^d_i + (K1 + 1) e_R + K2 e_V), e_R = p^d - p, e_V = v^d - v
    (the plant's drift is not cancelled; on a Clohessy-Wiltshire plant it is of order n^2 |p|)."""

    #: fields whose Yang2013TranslationalController attribute has another name (campaign.binding)
    leaf_paths: ClassVar[dict[str, str]] = {"nominal_mass": "mass"}
    K1: float = Field(
        0.005, gt=0, description="Position gain offset K1 (e_R gain K1 + 1) [1/s^2], > 0."
    )
    K2: float = Field(0.01, gt=0, description="Velocity gain K2 [1/s], > 0.")
    nominal_mass: float | list[float] = Field(
        NOMINAL_MASS,
        description="Mass M_i used by the law [kg] (one or per spacecraft; default 150 kg, Yang2013's "
        "spacecraft, a stated nominal value: never the plant's true masses).",
    )
    desired_position: Vec3Expr = Field(
        ("0", "0", "0"), description="Desired position p^d per axis, expressions in t [s], i [m]."
    )

    @model_validator(mode="after")
    def _masses(self):
        m = self.nominal_mass
        values = [m] if isinstance(m, (int, float)) else list(m)
        if any(not (v > 0 and math.isfinite(v)) for v in values):
            raise ValueError("nominal_mass: every mass must be finite and > 0 kg")
        return self


class Yang2013RelativeSection(Yang2013TranslationalSection):
    coupling: float | list[float] = Field(
        1.0,
        description="beta_i [-] in [0, 1] (one or per spacecraft): weight of the referenced spacecraft's "
        "received formation error; 1 keeps the offset relative to them, 0 tracks the own slot.",
    )

    @model_validator(mode="after")
    def _coupling(self):
        values = [self.coupling] if isinstance(self.coupling, (int, float)) else list(self.coupling)
        if any(not (0.0 <= v <= 1.0) for v in values):
            raise ValueError(f"coupling: every beta_i must lie in [0, 1], got {values}")
        return self


def translational_law(
    ctx: BuildContext,
    nominal_mass: float | list[float],
    K1: float,
    K2: float,
    desired_position: Vec3Expr = ("0", "0", "0"),
) -> Yang2013TranslationalController:
    """Yang2013's law (12) with the stated masses M_i [kg] and gains K1 [1/s^2], K2 [1/s] (the one
    builder of the law: the catalog's Yang2013 controller types use it)."""
    from formation_ftc.components.controllers.yang2013_individual import (
        Yang2013TranslationalController,
    )

    n = ctx.count
    px, py, pz = desired_position
    return Yang2013TranslationalController(
        count=n,
        mass=as_float(per_spacecraft(nominal_mass, n, "controller.nominal_mass")),
        K1=as_float(K1),
        K2=as_float(K2),
        desired_position=(str(px), str(py), str(pz)),
    )


def _yang2013_law(
    sec: Yang2013TranslationalSection, ctx: BuildContext
) -> Yang2013TranslationalController:
    return translational_law(ctx, sec.nominal_mass, sec.K1, sec.K2, sec.desired_position)


def _yang2013_relative(
    sec: Yang2013RelativeSection, ctx: BuildContext
) -> NeighbourRelativeController:
    from formation_ftc.components.controllers.neighbour_relative import NeighbourRelativeController

    if ctx.section("network") is None:
        raise ValueError(
            "controller.type = 'yang2013-relative' references other spacecraft through the "
            "network: add a [network] (e.g. type = 'graph' or 'delayed-graph')"
        )
    return NeighbourRelativeController(
        law=_yang2013_law(sec, ctx),
        coupling=as_float(per_spacecraft(sec.coupling, ctx.count, "controller.coupling")),
    )


register_component_type(
    "controller",
    "yang2013-translational",
    Yang2013TranslationalSection,
    _yang2013_law,
    "Yang2013 feedback-linearising translational law (12), own desired slot, no messages",
)
register_component_type(
    "controller",
    "yang2013-relative",
    Yang2013RelativeSection,
    _yang2013_relative,
    "Yang2013 law (12) keeping each spacecraft's offset relative to the (delayed) formation "
    "errors received from the spacecraft it references",
)
