"""Gravity-gradient torque on a rigid spacecraft in a circular orbit, and its small-angle librations.

Frames (as in the rest of the package):

* **inertial frame I**: Earth-centred; the circular orbit of radius ``r`` [m] lies in its x-y plane and
  is flown prograde (angular momentum along +z_I), so the position is
  ``r_I(t) = r [cos u, sin u, 0]`` with the argument of latitude ``u(t) = u0 + n t`` [rad] and the orbit
  rate ``n = sqrt(mu / r^3)`` [rad/s];
* **LVLH frame L** (local vertical, local horizontal): x radial (from the Earth's centre towards the
  spacecraft, zenith), y along-track (the velocity direction), z orbit normal. Its axes in inertial
  components are the columns of ``C_IL = Rz(u)``, and it rotates at ``n`` about its z axis;
* **body frame B**: the spacecraft's principal or non-principal axes; the attitude quaternion
  ``q = [q_v, q4]`` (vector first) maps body to inertial components, ``v_I = C(q) v_B``
  (:func:`formation_ftc.core.quaternion.rotation_matrix`).

Gravity-gradient torque (first order in the spacecraft size over r; point-mass Earth)::

    tau_gg = 3 mu / r^3  r_b x (J r_b)          r_b = C(q)^T r_I / r  (unit radial vector, body axes)

with the inertia ``J`` [kg m^2] about the centre of mass. It vanishes when a principal axis points along
the radial direction (the "aligned with LVLH" equilibria).

Small-angle librations about LVLH alignment (body x radial, y along-track, z orbit normal, principal
inertias J_x, J_y, J_z), from the linearised Euler equations in the frame rotating at n::

    pitch (rotation about the orbit normal, body z):
        w_pitch = n sqrt(3 (J_y - J_x) / J_z)                 stable when J_y > J_x
    roll / yaw (rotations about along-track y and radial x, coupled):
        w^4 - w^2 n^2 (1 + 3 k_r + k_r k_y) + 4 n^4 k_r k_y = 0
        k_r = (J_z - J_x) / J_y,   k_y = (J_z - J_y) / J_x

(the classical pitch / roll-yaw libration results, e.g. Hughes, *Spacecraft Attitude Dynamics*, ch. 9,
with the axes renamed: Hughes' roll axis is our y, pitch our z, yaw our x).

The attitude in a circular orbit under gravity gradient alone has the Jacobi integral (conserved)::

    H = 1/2 w_r^T J w_r - 1/2 n^2 o_b^T J o_b + 3/2 n^2 r_b^T J r_b

with ``w_r = omega - n o_b`` the body rate relative to LVLH and ``o_b`` the orbit normal in body axes.
"""

from __future__ import annotations

import math

import jax.numpy as jnp

from formation_ftc.core.orbit import MU_EARTH
from formation_ftc.core.quaternion import (
    quat_conjugate,
    quat_from_axis_angle,
    quat_multiply,
    rotation_matrix,
)
from formation_ftc.core.vector3 import matrix3

__all__ = [
    "orbit_rate",
    "argument_of_latitude",
    "circular_orbit_position",
    "lvlh_to_inertial",
    "quaternion_lvlh_to_inertial",
    "attitude_relative_to_lvlh",
    "radial_unit_in_body",
    "orbit_normal_in_body",
    "gravity_gradient_torque_unit",
    "gravity_gradient_torque_circular",
    "pitch_libration_frequency",
    "roll_yaw_libration_frequencies",
    "jacobi_integral",
]


def orbit_rate(radius, mu: float = MU_EARTH):
    """Orbit rate ``n = sqrt(mu / r^3)`` [rad/s] of a circular orbit of radius ``radius`` [m]."""
    return jnp.sqrt(mu / jnp.asarray(radius) ** 3)


def argument_of_latitude(t, radius, mu: float = MU_EARTH, u0=0.0):
    """``u(t) = u0 + n t`` [rad]; ``t`` [s], ``radius`` [m], ``u0`` [rad] at t = 0."""
    return u0 + orbit_rate(radius, mu) * jnp.asarray(t)


def circular_orbit_position(t, radius, mu: float = MU_EARTH, u0=0.0):
    """Inertial position ``r [cos u, sin u, 0]`` [m] on the circular orbit at time ``t`` [s]."""
    u = argument_of_latitude(t, radius, mu, u0)
    return radius * jnp.stack([jnp.cos(u), jnp.sin(u), jnp.zeros_like(u)], axis=-1)


def lvlh_to_inertial(u):
    """``C_IL = Rz(u)`` (..., 3, 3): LVLH components -> inertial components; columns are the radial,
    along-track and orbit-normal unit vectors in the inertial frame; ``u`` [rad]."""
    u = jnp.asarray(u)
    c, s = jnp.cos(u), jnp.sin(u)
    z, o = jnp.zeros_like(u), jnp.ones_like(u)
    return matrix3([[c, -s, z], [s, c, z], [z, z, o]])


def quaternion_lvlh_to_inertial(u):
    """Quaternion (vector first) of ``C_IL = Rz(u)``: ``[0, 0, sin(u/2), cos(u/2)]``; ``u`` [rad]."""
    u = jnp.asarray(u)
    return quat_from_axis_angle(jnp.broadcast_to(jnp.array([0.0, 0.0, 1.0]), (*u.shape, 3)), u)


def attitude_relative_to_lvlh(q, u):
    """Body -> LVLH quaternion ``q_L = q_IL^* (x) q`` (so ``C(q_L) = Rz(u)^T C(q)``); ``q`` (..., 4)
    body -> inertial, ``u`` argument of latitude [rad] broadcastable to ``q``'s leading shape."""
    q = jnp.asarray(q)
    q_il = jnp.broadcast_to(quaternion_lvlh_to_inertial(u), q.shape)
    return quat_multiply(quat_conjugate(q_il), q)


def radial_unit_in_body(q, u):
    """Unit radial (zenith) vector ``r_b = C(q)^T [cos u, sin u, 0]`` in body axes (..., 3)."""
    e_r = jnp.stack([jnp.cos(u), jnp.sin(u), jnp.zeros_like(u)], axis=-1)
    return jnp.einsum(
        "...ji,...j->...i", rotation_matrix(q), jnp.broadcast_to(e_r, jnp.shape(q)[:-1] + (3,))
    )


def orbit_normal_in_body(q):
    """Unit orbit normal ``o_b = C(q)^T [0, 0, 1]`` in body axes (..., 3) (the third row of C(q))."""
    return rotation_matrix(q)[..., 2, :]


def gravity_gradient_torque_unit(r_b, J, n2):
    """``tau_gg = 3 n^2 r_b x (J r_b)`` [N m] with ``n2 = mu / r^3`` [1/s^2].

    Parameters
    ----------
    r_b : (..., 3) unit radial vector in body axes [-]
    J : (..., 3, 3) inertia about the centre of mass [kg m^2] (broadcast against ``r_b``)
    n2 : mu / r^3 [1/s^2] (the squared orbit rate on a circular orbit)
    """
    Jr = jnp.einsum("...ij,...j->...i", jnp.asarray(J), r_b)
    return 3.0 * n2 * jnp.cross(r_b, Jr)  # tau_gg = 3 mu / r^3 r_b x J r_b


def gravity_gradient_torque_circular(t, q, J, radius, mu: float = MU_EARTH, u0=0.0):
    """Gravity-gradient torque [N m, body axes] at time ``t`` [s] on bodies of attitude ``q`` (..., 4)
    (body -> inertial) and inertia ``J`` (..., 3, 3) [kg m^2] flying the circular orbit of radius
    ``radius`` [m] (argument of latitude ``u0`` [rad] at t = 0)."""
    u = argument_of_latitude(t, radius, mu, u0)
    return gravity_gradient_torque_unit(radial_unit_in_body(q, u), J, mu / jnp.asarray(radius) ** 3)


def pitch_libration_frequency(J_principal, n: float) -> float:
    """Small-angle pitch libration ``n sqrt(3 (J_y - J_x) / J_z)`` [rad/s] about LVLH alignment.

    ``J_principal = (J_x, J_y, J_z)`` [kg m^2] along radial, along-track, orbit normal; pitch is the
    rotation about the orbit normal (body z). Raises ``ValueError`` when J_y <= J_x (pitch unstable).
    """
    jx, jy, jz = (float(v) for v in J_principal)
    if not jy > jx:
        raise ValueError(
            f"pitch is not a libration: J_y = {jy} <= J_x = {jx} kg m^2 (needs J_y > J_x)"
        )
    return n * math.sqrt(3.0 * (jy - jx) / jz)


def roll_yaw_libration_frequencies(J_principal, n: float) -> tuple[float, float]:
    """The two small-angle roll/yaw libration frequencies [rad/s] (lower, higher) about LVLH alignment.

    Roots in ``w^2`` of ``w^4 - w^2 n^2 (1 + 3 k_r + k_r k_y) + 4 n^4 k_r k_y = 0`` with
    ``k_r = (J_z - J_x) / J_y`` and ``k_y = (J_z - J_y) / J_x`` (module docstring). Raises
    ``ValueError`` when a root is not real and positive (no roll/yaw libration).
    """
    jx, jy, jz = (float(v) for v in J_principal)
    kr, ky = (jz - jx) / jy, (jz - jy) / jx
    b = 1.0 + 3.0 * kr + kr * ky
    c = 4.0 * kr * ky
    disc = b * b - 4.0 * c
    if disc < 0.0 or b <= 0.0 or c <= 0.0:
        raise ValueError(
            f"roll/yaw motion is not a libration for J = {J_principal} kg m^2 "
            f"(k_r = {kr:.4g}, k_y = {ky:.4g})"
        )
    lo, hi = 0.5 * (b - math.sqrt(disc)), 0.5 * (b + math.sqrt(disc))
    return n * math.sqrt(lo), n * math.sqrt(hi)


def jacobi_integral(omega, q, J, u, n):
    """Jacobi integral ``H`` [J] of the attitude in a circular orbit under gravity gradient (module
    docstring); ``omega`` (..., 3) inertial body rate [rad/s], ``q`` (..., 4), ``J`` (..., 3, 3) [kg m^2],
    ``u`` argument of latitude [rad], ``n`` orbit rate [rad/s]."""
    o_b = orbit_normal_in_body(q)
    r_b = radial_unit_in_body(q, u)
    w_r = omega - n * o_b

    def quad(v):
        return jnp.einsum("...i,...ij,...j->...", v, J, v)

    return 0.5 * quad(w_r) - 0.5 * n**2 * quad(o_b) + 1.5 * n**2 * quad(r_b)
