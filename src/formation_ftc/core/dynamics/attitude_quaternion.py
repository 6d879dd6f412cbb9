"""Rigid-body attitude with quaternions, gravity-gradient and disturbance torque (Yang2013 eq. (4)).

State ``s = [omega, q]`` (shape ``(..., 7)``): body angular velocity omega [rad/s] in the body frame
F_i and the attitude quaternion ``q = [q1, q2, q3, q4]`` (vector first, scalar last; see
:mod:`formation_ftc.core.quaternion`). Dynamics::

    J omega_dot = -omega x J omega + tau_g + tau + iota       # Yang2013 eq. (4)
    q_v_dot = 1/2 (q4 omega - omega x q_v),  q4_dot = -1/2 omega^T q_v
    tau_g = 3 mu / |R|^5  R x J R                             # gravity gradient, R in body axes

with the inertia matrix J [kg m^2] (symmetric positive definite), control torque tau [N m],
disturbance torque iota [N m] (|iota| <= iota_bar) and the position R [m] of the spacecraft from the
Earth's centre expressed in body axes.
"""

from __future__ import annotations

import jax.numpy as jnp

from formation_ftc.core.orbit import MU_EARTH
from formation_ftc.core.quaternion import quat_kinematics, rotation_matrix

__all__ = [
    "gravity_gradient_torque",
    "attitude_rhs",
    "rigid_body_quaternion_rates",
    "inverse_3x3",
    "angular_momentum_reference",
    "rotational_kinetic_energy",
]


def gravity_gradient_torque(R_body, J, mu: float = MU_EARTH):
    """``tau_g = 3 mu / |R|^5 R x (J R)`` [N m]; R_body (..., 3) [m], J (3, 3) [kg m^2]."""
    R_body, J = jnp.asarray(R_body), jnp.asarray(J)
    r = jnp.linalg.norm(R_body, axis=-1, keepdims=True)
    JR = jnp.einsum("ij,...j->...i", J, R_body)
    return 3.0 * mu / r**5 * jnp.cross(R_body, JR)


def attitude_rhs(t, state, J, torque=None, disturbance=None, R_body=None, mu: float = MU_EARTH):
    """Time derivative of ``[omega, q]`` under eq. (4).

    Parameters
    ----------
    t : time [s] (unused)
    state : (..., 7) ``[omega, q]`` [rad/s, -]
    J : (3, 3) inertia matrix [kg m^2]
    torque, disturbance : (..., 3) control torque tau and disturbance torque iota [N m]; None = zero
    R_body : (..., 3) position from the Earth's centre in body axes [m]; None = no gravity gradient
    mu : gravitational parameter [m^3/s^2]
    """
    state, J = jnp.asarray(state), jnp.asarray(J)
    omega, q = state[..., :3], state[..., 3:]
    Jw = jnp.einsum("ij,...j->...i", J, omega)
    total = -jnp.cross(omega, Jw)
    if R_body is not None:
        total = total + gravity_gradient_torque(R_body, J, mu)
    if torque is not None:
        total = total + jnp.asarray(torque)
    if disturbance is not None:
        total = total + jnp.asarray(disturbance)
    omega_dot = jnp.einsum("ij,...j->...i", jnp.linalg.inv(J), total)
    return jnp.concatenate([omega_dot, quat_kinematics(q, omega)], axis=-1)


def inverse_3x3(J):
    """Inverse of every (..., 3, 3) matrix by its adjugate, ``adj(J) / det(J)`` (rows of the adjugate
    transpose are the cross products of J's rows): plain arithmetic that XLA fuses, no LAPACK call
    inside a loop.

    Parameters
    ----------
    J : array_like, shape (..., 3, 3)
        Invertible matrices, e.g. inertias [kg m^2].

    Returns
    -------
    jax.Array, shape (..., 3, 3)
        The inverses (e.g. [1/(kg m^2)]).

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.core.dynamics.attitude_quaternion import inverse_3x3
    >>> J = np.array([np.diag([10.0, 20.0, 40.0]), [[2.0, 1.0, 0.0], [1.0, 2.0, 0.0], [0.0, 0.0, 1.0]]])
    >>> bool(np.allclose(inverse_3x3(J), np.linalg.inv(J)))
    True
    >>> np.asarray(inverse_3x3(J))[0].diagonal()
    array([0.1  , 0.05 , 0.025])
    """
    a, b, c = J[..., 0, :], J[..., 1, :], J[..., 2, :]
    cols = jnp.stack([jnp.cross(b, c), jnp.cross(c, a), jnp.cross(a, b)], axis=-1)
    det = jnp.sum(a * jnp.cross(b, c), axis=-1)
    return cols / det[..., None, None]


def rigid_body_quaternion_rates(omega, q, torque, J, gyroscopic: bool = True):
    """``(omega', q')`` of a rigid body with quaternion attitude, eq. (4) [rad/s^2, 1/s].

    ``J omega' = -omega x J omega + torque`` (the gyroscopic term only with ``gyroscopic``; at the
    error level of Yang2013 (5) it belongs to the drift Upsilon that the attitude law cancels);
    ``q' = 1/2 Omega(omega) q``. ``omega`` (..., 3) [rad/s], ``q`` (..., 4) vector first, ``torque``
    (..., 3) total torque [N m], ``J`` (3, 3) inertia [kg m^2].
    """
    J = jnp.asarray(J)
    total = torque
    if gyroscopic:
        total = -jnp.cross(omega, jnp.einsum("ij,...j->...i", J, omega)) + total
    omega_dot = jnp.einsum("ij,...j->...i", inverse_3x3(J), total)  # Yang2013 eq. (4) / (5)
    return omega_dot, quat_kinematics(q, omega)


def angular_momentum_reference(state, J):
    """Angular momentum in the reference frame, ``C(q) J omega`` [kg m^2/s] (torque-free invariant)."""
    state = jnp.asarray(state)
    omega, q = state[..., :3], state[..., 3:]
    Jw = jnp.einsum("ij,...j->...i", jnp.asarray(J), omega)
    return jnp.einsum("...ij,...j->...i", rotation_matrix(q), Jw)


def rotational_kinetic_energy(state, J):
    """``1/2 omega^T J omega`` [J] (torque-free invariant)."""
    state = jnp.asarray(state)
    omega = state[..., :3]
    return 0.5 * jnp.einsum("...i,ij,...j->...", omega, jnp.asarray(J), omega)
