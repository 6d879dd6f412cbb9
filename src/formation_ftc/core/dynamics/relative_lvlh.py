"""Nonlinear relative motion about an elliptic Keplerian reference orbit in the LVLH frame.

Li et al. 2020, eqs. (1)-(4), with the errata applied:

* E000-01: x radial (outward), y along-track (in-plane), z orbit normal -- the equations fix the axes;
* E000-02: rho_dot_i = v_i;
* E000-03: r_i = ||[r_c + x_i, y_i, z_i]|| is the distance from Earth's centre to spacecraft i.

Per spacecraft i (mass m_i [kg], force in N)::

    m_i v_dot_i = C_i v_i + D_i rho_i + n_i + h_i + F_i                      # Li2020 eq. (1)
    C_i = 2 m_i theta_dot [[0,1,0],[-1,0,0],[0,0,0]]                        # eq. (2)
    D_i = -m_i mu/r_i^3 I + m_i [[thd^2, thdd, 0],[-thdd, thd^2, 0],[0,0,0]]  # eq. (3)
    n_i = mu m_i [-r_c/r_i^3 + 1/r_c^2, 0, 0]                               # eq. (4)

C_i, D_i and n_i are proportional to m_i, so :func:`natural_acceleration` returns the mass-free
per-unit-mass acceleration (C_i v_i + D_i rho_i + n_i)/m_i [m/s^2], which is also the known part of the
regressor Y_i of eq. (8).

The reference true anomaly theta_c is integrated with the state (``theta_dot = sqrt(mu/p^3)
(1 + e cos theta)^2``); theta_ddot follows in closed form. State layout (pytree)::

    {"theta": () [rad], "rho": (N, 3) [m], "v": (N, 3) [m/s]}

All functions are pure ``jax.numpy``; orbit parameters may be traced arrays (Monte Carlo).
"""

from __future__ import annotations

import jax.numpy as jnp

__all__ = [
    "reference_rates",
    "natural_acceleration",
    "natural_acceleration_from_rates",
    "relative_lvlh_rhs",
    "lvlh_from_inertial",
]


def reference_rates(theta, p, e, mu):
    """Radius and true-anomaly rates of the reference orbit.

    Parameters
    ----------
    theta : true anomaly [rad]
    p : semi-latus rectum a (1 - e^2) [m]
    e : eccentricity [-]
    mu : gravitational parameter [m^3/s^2]

    Returns
    -------
    (r_c [m], theta_dot [rad/s], theta_ddot [rad/s^2])
    """
    one_ecos = 1.0 + e * jnp.cos(theta)
    r_c = p / one_ecos
    n2 = mu / p**3
    theta_dot = jnp.sqrt(n2) * one_ecos**2
    theta_ddot = -2.0 * n2 * e * jnp.sin(theta) * one_ecos**3
    return r_c, theta_dot, theta_ddot


def natural_acceleration(rho, v, theta, p, e, mu):
    """(C_i v_i + D_i rho_i + n_i) / m_i [m/s^2] for positions ``rho`` (..., 3) [m], velocities ``v`` [m/s].

    Li2020 eqs. (1)-(4) divided by m_i (E000-01, E000-03).
    """
    return natural_acceleration_from_rates(rho, v, *reference_rates(theta, p, e, mu), mu)


def natural_acceleration_from_rates(rho, v, r_c, theta_dot, theta_ddot, mu):
    """:func:`natural_acceleration` from the reference-orbit values ``reference_rates`` returns.

    Lets a caller evaluate the (run-independent) orbit terms once and share them: XLA fuses a scalar
    producer into its single elementwise consumer and then recomputes it, cos and sin included, for
    every element of the (runs, N, 3) arrays.
    """
    thd, thdd = theta_dot, theta_ddot
    x, y, z = rho[..., 0], rho[..., 1], rho[..., 2]
    vx, vy = v[..., 0], v[..., 1]
    r_i = jnp.sqrt((r_c + x) ** 2 + y**2 + z**2)  # E000-03
    g = mu / r_i**3
    # eqs. (2)-(4)
    ax = 2.0 * thd * vy + thd**2 * x + thdd * y - g * x - mu * r_c / r_i**3 + mu / r_c**2
    ay = -2.0 * thd * vx - thdd * x + thd**2 * y - g * y
    az = -g * z
    return jnp.stack([ax, ay, az], axis=-1)


def relative_lvlh_rhs(t, state, force, mass, p, e, mu):
    """Time derivative of ``{"theta", "rho", "v"}`` under total external force ``force`` (N, 3) [N].

    ``force`` is h_i + F_i of eq. (1); ``mass`` (N,) [kg]. ``t`` is unused (autonomous model) but kept
    for the integrator signature.
    """
    del t
    theta, rho, v = state["theta"], state["rho"], state["v"]
    _, thd, _ = reference_rates(theta, p, e, mu)
    acc = natural_acceleration(rho, v, theta, p, e, mu) + force / mass[..., None]
    return {"theta": thd, "rho": v, "v": acc}  # E000-02: rho_dot = v


def lvlh_from_inertial(r_chief, v_chief, r_deputy, v_deputy):
    """Relative position and velocity of a deputy in the chief's rotating LVLH frame (numpy or jax arrays).

    x along r_chief, z along the orbit normal h = r x v, y = z x x. The relative velocity is taken in the
    rotating frame: v_rel = R (v_d - v_c - omega x (r_d - r_c)), omega = h / |r|^2.
    Shapes (..., 3); returns (rho [m], v [m/s]).
    """
    r_chief, v_chief = jnp.asarray(r_chief), jnp.asarray(v_chief)
    h = jnp.cross(r_chief, v_chief)
    ex = r_chief / jnp.linalg.norm(r_chief, axis=-1, keepdims=True)
    ez = h / jnp.linalg.norm(h, axis=-1, keepdims=True)
    ey = jnp.cross(ez, ex)
    R = jnp.stack([ex, ey, ez], axis=-2)  # rows are the LVLH axes in inertial coordinates
    omega = h / jnp.sum(r_chief**2, axis=-1, keepdims=True)
    dr = jnp.asarray(r_deputy) - r_chief
    dv = jnp.asarray(v_deputy) - v_chief - jnp.cross(omega, dr)
    rho = jnp.einsum("...ij,...j->...i", R, dr)
    vel = jnp.einsum("...ij,...j->...i", R, dv)
    return rho, vel
