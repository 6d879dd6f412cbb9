"""Controller ``yang2013-translational``: Yang2013's feedback-linearising formation law (12) on the
measured (N, 6) relative state of any translational plant, tracking each spacecraft's own desired
position; it exchanges no messages (the loop refuses it with a delayed network).

The equations and the component are in :mod:`formation_ftc.components.controllers._yang2013` (shared
with ``yang2013-relative``, ``yang2013-force-torque`` and ``yang2013-attitude``); the law's on-board
masses are stated (``nominal_mass``, default 150 kg, Yang2013's spacecraft).
"""

from __future__ import annotations

from pydantic import Field

from formation_ftc.components._flight_defaults import YANG2013_NOMINAL_MASS
from formation_ftc.components._registry import BuildContext, register
from formation_ftc.components._sections import Masses, Vec3Expr
from formation_ftc.components.controllers._yang2013 import (
    Yang2013TranslationalController,
    translational_law,
)
from formation_ftc.config.base import StrictModel

__all__ = ["Yang2013TranslationalSection"]


class Yang2013TranslationalSection(StrictModel):
    """Yang2013 eq. (12): f_i = M_i (a^d_i + (K1 + 1) e_R + K2 e_V), e_R = p^d - p, e_V = v^d - v
    (the plant's drift is not cancelled; on a Clohessy-Wiltshire plant it is of order n^2 |p|)."""

    K1: float = Field(
        0.005, gt=0, description="Position gain offset K1 (e_R gain K1 + 1) [1/s^2], > 0."
    )
    K2: float = Field(0.01, gt=0, description="Velocity gain K2 [1/s], > 0.")
    nominal_mass: Masses = Field(
        YANG2013_NOMINAL_MASS,
        description="Mass M_i used by the law [kg] (one or per spacecraft; default 150 kg, Yang2013's "
        "spacecraft, a stated nominal value: never the plant's true masses).",
    )
    desired_position: Vec3Expr = Field(
        ("0", "0", "0"), description="Desired position p^d per axis, expressions in t [s], i [m]."
    )


def _build(sec: Yang2013TranslationalSection, ctx: BuildContext) -> Yang2013TranslationalController:
    """The controller of a validated ``[controller] type = "yang2013-translational"`` section."""
    return translational_law(ctx, sec)


register(
    "controller",
    "yang2013-translational",
    Yang2013TranslationalSection,
    _build,
    "Yang2013 feedback-linearising translational law (12), own desired slot, no messages",
)
