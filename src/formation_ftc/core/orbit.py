"""Keplerian reference orbit: true anomaly, its rates, radius, mean motion and period.

Used as the virtual reference of the relative-motion models (Li2020 Sec. II).
All quantities SI: metres, seconds, radians; gravitational parameter in m^3/s^2.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax.numpy as jnp
import numpy as np

from formation_ftc.core.constants import MU_EARTH

__all__ = ["MU_EARTH", "KeplerOrbit", "solve_kepler", "true_anomaly_at"]


@dataclass(frozen=True)
class KeplerOrbit:
    """Elliptic Keplerian orbit.

    Parameters
    ----------
    a : semi-major axis [m]
    e : eccentricity [-], 0 <= e < 1
    theta0 : true anomaly at t = 0 [rad]
    mu : gravitational parameter [m^3/s^2]
    """

    a: float
    e: float
    theta0: float = 0.0
    mu: float = MU_EARTH

    def __post_init__(self) -> None:
        if not self.a > 0:
            raise ValueError(f"orbit.a must be > 0 m, got {self.a}")
        if not 0.0 <= self.e < 1.0:
            raise ValueError(f"orbit.e must be in [0, 1), got {self.e}")
        if not self.mu > 0:
            raise ValueError(f"orbit.mu must be > 0 m^3/s^2, got {self.mu}")

    @property
    def semi_latus_rectum(self) -> float:
        """p = a (1 - e^2) [m]."""
        return self.a * (1.0 - self.e**2)

    @property
    def mean_motion(self) -> float:
        """n = sqrt(mu / a^3) [rad/s]."""
        return float(np.sqrt(self.mu / self.a**3))

    @property
    def period(self) -> float:
        """T = 2 pi / n [s]."""
        return 2.0 * np.pi / self.mean_motion

    def radius(self, theta):
        """r(theta) = p / (1 + e cos theta) [m]."""
        return self.semi_latus_rectum / (1.0 + self.e * jnp.cos(theta))

    def theta_dot(self, theta):
        """d theta/dt = sqrt(mu/p^3) (1 + e cos theta)^2 [rad/s]."""
        p = self.semi_latus_rectum
        return jnp.sqrt(self.mu / p**3) * (1.0 + self.e * jnp.cos(theta)) ** 2

    def theta_ddot(self, theta):
        """d^2 theta/dt^2 = -2 (mu/p^3) e sin theta (1 + e cos theta)^3 [rad/s^2]."""
        p = self.semi_latus_rectum
        return (
            -2.0 * (self.mu / p**3) * self.e * jnp.sin(theta) * (1.0 + self.e * jnp.cos(theta)) ** 3
        )


def solve_kepler(mean_anomaly: np.ndarray | float, e: float, tol: float = 1e-15) -> np.ndarray:
    """Eccentric anomaly E from Kepler's equation M = E - e sin E (Newton iteration, numpy)."""
    M_all = np.asarray(mean_anomaly, dtype=float)
    # reduce to (-pi, pi] so that Newton starts near the root; add the revolutions back at the end
    M = np.remainder(M_all + np.pi, 2 * np.pi) - np.pi
    E = M + e * np.sin(M) if e < 0.8 else np.pi * np.sign(M) + (M == 0) * 0.0
    for _ in range(60):
        dE = (E - e * np.sin(E) - M) / (1.0 - e * np.cos(E))
        E = E - dE
        if np.all(np.abs(dE) < tol):
            break
    return E + (M_all - M)


def true_anomaly_at(orbit: KeplerOrbit, t: np.ndarray | float) -> np.ndarray:
    """True anomaly [rad] at time t [s] from Kepler's equation (independent of the ODE for theta).

    The returned angle is continuous (unwrapped), starting from ``orbit.theta0``.
    """
    e = orbit.e
    t = np.asarray(t, dtype=float)
    # eccentric and mean anomaly at t = 0
    E0 = 2.0 * np.arctan2(
        np.sqrt(1 - e) * np.sin(orbit.theta0 / 2), np.sqrt(1 + e) * np.cos(orbit.theta0 / 2)
    )
    M0 = E0 - e * np.sin(E0)
    M = M0 + orbit.mean_motion * t
    E = solve_kepler(M, e)
    theta = 2.0 * np.arctan2(np.sqrt(1 + e) * np.sin(E / 2), np.sqrt(1 - e) * np.cos(E / 2))
    # unwrap consistently with M (number of full revolutions)
    # theta - M is bounded by about 2e, so rounding recovers the number of full revolutions
    revs = np.round((M - theta) / (2 * np.pi))
    return theta + 2 * np.pi * revs
