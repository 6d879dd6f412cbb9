"""Evaluation ``navigation-consistency``: is the navigation filter a law flies on as confident as it is
right? Truth-side scores (records and metrics only) of a filter's consistency.

A consistent Kalman filter's estimation error ``e = x_hat - x`` has the covariance ``P`` it states, so
the normalised estimation error squared ``NEES = e^T P^-1 e`` of a 6-state estimate is chi-square with 6
degrees of freedom, and so is the normalised innovation squared ``NIS`` the filter computes on board
(Bar-Shalom, Li and Kirubarajan, *Estimation with Applications to Tracking and Navigation*, 2001, ch.
5.4). An overconfident filter (process noise too small for the truth it flies on) shows a mean NEES far
above 6 and few samples inside the two-sided chi-square band.

Needs ``navigation-records`` (an estimator the law flies on that records ``navigation_estimate``,
``navigation_covariance`` and ``navigation_nis``: ``relative-navigation-filter``, or ``residual-fdi``
with ``fly_on_filter = true``) and the plant's ``lvlh-relative-state`` (the true LVLH relative
``position`` and ``velocity`` the sensors measure).
"""

from __future__ import annotations

import jax.numpy as jnp
from pydantic import Field

from formation_ftc.components._registry import BuildContext, register
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import Evaluation, Signal, component, static

__all__ = ["NavigationConsistency", "NavigationConsistencySection", "chi2_band"]

#: state components of the relative navigation (position and velocity, LVLH)
STATES = 6


def chi2_band(confidence: float, dof: int = STATES) -> tuple[float, float]:
    """The two-sided chi-square band that holds ``confidence`` of a consistent filter's NEES or NIS.

    Parameters
    ----------
    confidence : float
        Probability inside the band, in (0, 1) [-].
    dof : int
        Degrees of freedom (the filter's states) [-].

    Returns
    -------
    tuple of float
        The band's lower and upper edges [-].

    Examples
    --------
    >>> lo, hi = chi2_band(0.95)
    >>> round(lo, 3), round(hi, 3)
    (1.237, 14.449)
    """
    from scipy.stats import chi2

    tail = (1.0 - confidence) / 2.0
    return float(chi2.ppf(tail, dof)), float(chi2.ppf(1.0 - tail, dof))


@component
class NavigationConsistency(Evaluation):
    """At every sample, per spacecraft: ``nees`` = e^T P^-1 e with e the filter's estimate minus the
    true LVLH relative state (``position``, ``velocity``) and P its stated covariance after the
    update; ``nees_in_band`` and ``nis_in_band`` (1 or 0): the NEES (the filter's NIS) inside the
    two-sided chi-square band [``low``, ``high``] of 6 degrees of freedom at the stated confidence. Their
    means over time are the league's consistency scores: a mean NEES near 6 and in-band fractions near
    the confidence say the filter's stated noise fits the truth."""

    low: float = static()
    high: float = static()

    def needs(self) -> dict[str, str]:
        return {
            "navigation-records": "score the filter the law flies on",
            "lvlh-relative-state": "the true relative state the estimate is compared with",
        }

    def signals(self):
        return (
            Signal("nees", ("spacecraft",), "1", "normalised estimation error squared (6 states)"),
            Signal("nees_in_band", ("spacecraft",), "1", "NEES inside the chi-square band"),
            Signal("nis_in_band", ("spacecraft",), "1", "NIS inside the chi-square band"),
        )

    def outputs(self, signals):
        truth = jnp.concatenate([signals["position"], signals["velocity"]], axis=-1)
        error = jnp.asarray(signals["navigation_estimate"]) - truth  # (N, 6)
        p = jnp.asarray(signals["navigation_covariance"])
        nees = jnp.einsum("ni,ni->n", error, jnp.linalg.solve(p, error.T).T)
        nis = jnp.asarray(signals["navigation_nis"])

        def inside(v):
            return jnp.where((v >= self.low) & (v <= self.high), 1.0, 0.0)

        return {"nees": nees, "nees_in_band": inside(nees), "nis_in_band": inside(nis)}


class NavigationConsistencySection(StrictModel):
    """Consistency scores (NEES, NIS) of the navigation filter a law flies on."""

    confidence: float = Field(
        0.95, gt=0, lt=1, description="Probability of the two-sided chi-square band [-]."
    )


def _build(sec: NavigationConsistencySection, ctx: BuildContext) -> NavigationConsistency:
    low, high = chi2_band(sec.confidence)
    return NavigationConsistency(low=low, high=high)


register(
    "evaluation",
    "navigation-consistency",
    NavigationConsistencySection,
    _build,
    "NEES and NIS of the navigation filter a law flies on, against their chi-square band",
)
