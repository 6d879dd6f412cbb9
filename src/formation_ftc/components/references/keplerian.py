"""Reference ``keplerian``: the Keplerian reference orbit (virtual chief) for relative motion in its
LVLH frame; eccentricity 0 gives a circular orbit."""

from __future__ import annotations

from typing import Any

from pydantic import Field

from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.components._sections import section_floats
from formation_ftc.config.base import StrictModel
from formation_ftc.core.constants import MU_EARTH
from formation_ftc.core.dynamics.relative_lvlh import reference_rates
from formation_ftc.sim.components import Reference, component
from formation_ftc.sim.contract import as_float

__all__ = ["KeplerianReference", "KeplerianSection"]


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

    def provides(self) -> frozenset[str]:
        return frozenset({"reference-orbit"})


class KeplerianSection(StrictModel):
    """The reference orbit's elements (the builder turns ``semi_major_axis`` and ``eccentricity`` into
    the semi-latus rectum p = a (1 - e^2))."""

    semi_major_axis: float = builder_input(
        gt=0, description="Semi-major axis of the reference orbit [m]."
    )
    eccentricity: float = Field(0.0, ge=0, lt=1, description="Eccentricity [-].")
    true_anomaly0: float = Field(0.0, description="True anomaly at t = 0 [rad].")
    mu: float = Field(MU_EARTH, gt=0, description="Gravitational parameter [m^3/s^2].")


def _build(sec: KeplerianSection, ctx: BuildContext) -> KeplerianReference:
    """The reference of a validated ``[reference] type = "keplerian"`` section."""
    p = sec.semi_major_axis * (1.0 - sec.eccentricity**2)
    return KeplerianReference(
        semi_latus_rectum=as_float(p),
        **section_floats(sec, "eccentricity", "mu", "true_anomaly0"),
    )


register(
    "reference",
    "keplerian",
    KeplerianSection,
    _build,
    "Keplerian reference orbit (virtual chief); eccentricity 0 gives a circular orbit",
)
