"""Desired formation trajectories that formation controllers carry as their own time signals."""

from __future__ import annotations

from typing import Any

from formation_ftc.core.rotating_formation import desired_trajectory
from formation_ftc.sim.components import component

__all__ = ["RotatingFormation"]


@component
class RotatingFormation:
    """Rotating, expanding formation with a moving centre (Li2020 Sec. IV-A;
    :mod:`formation_ftc.core.rotating_formation`). :meth:`at` returns the desired position, velocity and
    acceleration ``rho_d, v_d, a_d`` and the formation part ``rho_f`` (each (N, 3) [m, m/s, m/s^2])."""

    offsets: Any  # rho_bar_iF (N, 3) [m]
    chi: Any  # [s^2]
    rotation: Any  # final rotation angle about y [rad]
    growth: Any  # final relative size change [-]
    centre: Any  # (3,) final centre offset [m]

    def at(self, t) -> dict:
        rho_d, v_d, a_d, rho_f = desired_trajectory(
            t, self.offsets, self.chi, self.rotation, self.growth, self.centre
        )
        return {"rho_d": rho_d, "v_d": v_d, "a_d": a_d, "rho_f": rho_f}
