"""Keplerian reference orbit (virtual chief) for relative motion in its LVLH frame."""

from __future__ import annotations

from typing import Any

from formation_ftc.core.dynamics.relative_lvlh import reference_rates
from formation_ftc.sim.components import Reference, component

__all__ = ["KeplerianReference"]


@component
class KeplerianReference(Reference):
    """Elliptic Keplerian reference orbit, integrated through its true anomaly theta [rad]::

        theta_dot = sqrt(mu / p^3) (1 + e cos theta)^2                     (Li2020 eqs. (2)-(4))

    State: theta [rad]. :meth:`values` returns ``{"theta" [rad], "r_c" [m], "theta_dot" [rad/s],
    "theta_ddot" [rad/s^2]}`` (works on a stacked vector of stage values as well).
    """

    semi_latus_rectum: Any  # p = a (1 - e^2) [m]
    eccentricity: Any  # e [-]
    mu: Any  # gravitational parameter [m^3/s^2]
    true_anomaly0: Any = 0.0  # theta(t0) [rad]

    def initial_state(self):
        return self.true_anomaly0

    def rate(self, r):
        return reference_rates(r, self.semi_latus_rectum, self.eccentricity, self.mu)[1]

    def values(self, r):
        r_c, thd, thdd = reference_rates(r, self.semi_latus_rectum, self.eccentricity, self.mu)
        return {"theta": r, "r_c": r_c, "theta_dot": thd, "theta_ddot": thdd}
