"""Rotating, expanding desired formation with a moving centre (Li et al. 2020, Sec. IV-A), with exact
analytic first and second time derivatives.

::

    rho_bar_iF = R [cos(phi_i)/2, -sin(phi_i), sqrt(3)/2 cos(phi_i)]        (E000-10)
    g(t) = 1 - exp(-t^2 / (2 chi)),   chi = -(0.5 T_c)^2 / (2 ln 1e-6)      (E000-09)
    phi_bar(t) = rotation g(t),  lambda(t) = 1 + growth g(t)
    rho_iF = lambda R_y(phi_bar) rho_bar_iF,   rho_o^d = g(t) centre_offset
    rho_i^d = rho_iF + rho_o^d,  v_i^d and a_i^d their analytic first and second derivatives.

Units: m, m/s, m/s^2, s, rad.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np

from formation_ftc.core.timefunctions import smooth_transition

__all__ = ["formation_offsets", "chi_from_period", "desired_trajectory", "formation_relative"]


def formation_offsets(radius: float, phases) -> np.ndarray:
    """rho_bar_iF (N, 3) [m] (E000-10 sign pattern)."""
    ph = np.asarray(phases, dtype=float)
    return radius * np.stack(
        [0.5 * np.cos(ph), -np.sin(ph), (math.sqrt(3) / 2) * np.cos(ph)], axis=-1
    )


def chi_from_period(period: float, fraction: float = 0.5, residual: float = 1e-6) -> float:
    """chi [s^2] such that g(fraction * period) = 1 - residual: -(fraction T_c)^2 / (2 ln residual)."""
    return -((fraction * period) ** 2) / (2.0 * math.log(residual))


def _rotations(phi):
    c, s = jnp.cos(phi), jnp.sin(phi)
    z, o = jnp.zeros_like(c), jnp.ones_like(c)
    R = jnp.array([[c, z, -s], [z, o, z], [s, z, c]])
    R1 = jnp.array([[-s, z, -c], [z, z, z], [c, z, -s]])  # dR/dphi
    R2 = jnp.array([[-c, z, s], [z, z, z], [-s, z, -c]])  # d2R/dphi2
    return R, R1, R2


def formation_relative(t, rho_bar, chi, rotation, growth):
    """(rho_iF, v_iF, a_iF), each (N, 3): the rotating, expanding part of the desired formation."""
    g, gd, gdd = smooth_transition(t, chi)
    phi, phid, phidd = rotation * g, rotation * gd, rotation * gdd
    lam, lamd, lamdd = 1.0 + growth * g, growth * gd, growth * gdd
    R, R1, R2 = _rotations(phi)
    Rd = phid * R1
    Rdd = phidd * R1 + phid**2 * R2
    rho = lam * rho_bar @ R.T
    vel = rho_bar @ (lamd * R + lam * Rd).T
    acc = rho_bar @ (lamdd * R + 2.0 * lamd * Rd + lam * Rdd).T
    return rho, vel, acc


def desired_trajectory(t, rho_bar, chi, rotation, growth, centre):
    """(rho_i^d, v_i^d, a_i^d, rho_iF), (N, 3) each, at time t [s]."""
    g, gd, gdd = smooth_transition(t, chi)
    rho_f, v_f, a_f = formation_relative(t, rho_bar, chi, rotation, growth)
    centre = jnp.asarray(centre)
    return rho_f + g * centre, v_f + gd * centre, a_f + gdd * centre, rho_f
