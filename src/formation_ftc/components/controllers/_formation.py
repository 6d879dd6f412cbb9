"""The rotating desired formation that Li2020's laws (``li2020-adaptive``, ``sir-ftc``) carry as their
own time signal, and its TOML table ``[controller.formation]``."""

from __future__ import annotations

from typing import Any, cast

import numpy as np
from pydantic import Field, model_validator

from formation_ftc.components._registry import builder_input
from formation_ftc.components._sections import Vec3, section_floats
from formation_ftc.config.base import StrictModel
from formation_ftc.core.rotating_formation import desired_trajectory
from formation_ftc.sim.components import component
from formation_ftc.sim.contract import as_float

__all__ = ["RotatingFormation", "FormationSection"]


@component
class RotatingFormation:
    """Rotating, expanding formation with a moving centre (Li2020 Sec. IV-A;
    :mod:`formation_ftc.core.rotating_formation`). :meth:`at` returns the desired position, velocity and
    acceleration ``rho_d, v_d, a_d`` and the formation part ``rho_f`` (each (N, 3) [m, m/s, m/s^2])."""

    offsets: Any  # rho_bar_iF (N, 3) [m]
    chi: Any  # [s^2]
    rotation: Any  # final rotation angle about y [rad]
    growth: Any  # final relative size change [-]
    centre_offset: Any  # (3,) final centre offset [m]

    def at(self, t) -> dict:
        rho_d, v_d, a_d, rho_f = desired_trajectory(
            t, self.offsets, self.chi, self.rotation, self.growth, self.centre_offset
        )
        return {"rho_d": rho_d, "v_d": v_d, "a_d": a_d, "rho_f": rho_f}


class FormationSection(StrictModel):
    """The desired formation: offsets on a circle (``radius``, ``phase``) or explicit ``offsets``,
    rotated, grown and moved over the manoeuvre of time constant ``chi`` (or ``period``)."""

    radius: float | None = builder_input(
        None, gt=0, description="Formation radius [m] (with `phase`; or give `offsets`)."
    )
    phase: list[float] | None = builder_input(
        None, description="Phase of each spacecraft on the formation circle [rad]."
    )
    offsets: list[Vec3] | None = Field(
        None,
        description=(
            "Explicit formation offsets rho_bar_iF per spacecraft [m], LVLH (instead of radius and phase)."
        ),
    )
    rotation: float = Field(0.0, description="Final rotation about the LVLH y axis [rad].")
    growth: float = Field(0.0, description="Final relative size change [-].")
    centre_offset: Vec3 = Field((0.0, 0.0, 0.0), description="Final centre offset [m].")
    chi: float | None = Field(None, gt=0, description="Time constant of the manoeuvre [s^2].")
    period: float | None = builder_input(
        None, gt=0, description="Reference period used to derive chi when chi is not given [s]."
    )

    @model_validator(mode="after")
    def _geometry(self):
        if (self.offsets is None) == (self.radius is None or self.phase is None):
            raise ValueError("controller.formation: give either radius and phase, or offsets")
        return self

    def component(self, n: int) -> RotatingFormation:
        """The formation of ``n`` spacecraft (errors name ``controller.formation.<field>``)."""
        from formation_ftc.core.rotating_formation import chi_from_period, formation_offsets

        if self.offsets is not None:
            if len(self.offsets) != n:
                raise ValueError(
                    f"controller.formation.offsets: {len(self.offsets)} offsets for {n} spacecraft"
                )
            offsets = np.asarray(self.offsets, dtype=float)
        else:
            phase = cast(list, self.phase)
            if len(phase) != n:
                raise ValueError(
                    f"controller.formation.phase: {len(phase)} values for {n} spacecraft"
                )
            offsets = formation_offsets(cast(float, self.radius), phase)
        if self.chi is None and self.period is None:
            raise ValueError("controller.formation: give chi [s^2] or period [s]")
        chi = self.chi if self.chi is not None else chi_from_period(cast(float, self.period))
        return RotatingFormation(
            offsets=as_float(offsets),
            chi=as_float(chi),
            **section_floats(self, "rotation", "growth", "centre_offset"),
        )
