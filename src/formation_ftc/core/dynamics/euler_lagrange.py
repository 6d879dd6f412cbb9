"""Rigid-body attitude as an Euler-Lagrange (EL) system in Euler angles (Mehrabian et al., eqs. (1), (27), (28)).

Generalised coordinates ``q = [theta, phi, psi]`` (pitch, roll, yaw) [rad] of the Z-Y-X (yaw-pitch-roll)
sequence: the body-to-inertial rotation is ``R = Rz(psi) Ry(theta) Rx(phi)``. Body rates ``omega``
[rad/s] (body frame), inertia ``J`` [kg m^2] (3x3, symmetric positive definite), generalised forces
``u`` [N m] conjugate to ``q`` (power ``u^T q_dot = tau_b^T omega``, so the body torque is
``tau_b = R_bar^T u``).

Kinematics (E003-08: the printed R_bar is the standard Z-Y-X matrix for the ordering
[phi, theta, psi]; with q = [theta, phi, psi] its first two rows are swapped)::

    theta_dot = c_phi w_y - s_phi w_z
    phi_dot   = w_x + s_phi t_theta w_y + c_phi t_theta w_z
    psi_dot   = (s_phi w_y + c_phi w_z) / c_theta              i.e.  q_dot = R_bar(q) omega

EL form (27)-(28) with ``W = R_bar^{-1}`` (defined everywhere, singular where c_theta = 0)::

    D(q)         = W^T J W
    C(q, q_dot)  = -W^T S(J W q_dot) W + W^T J W_dot            (g = 0 for attitude)
    D q_ddot + C q_dot = u

``D_dot - 2 C`` is skew-symmetric (property P3 as corrected in E003-07). The representation is singular
at theta = +-90 deg (R_bar has 1/cos(theta); D loses rank): :func:`check_away_from_singularity` rejects
such attitudes.

Two propagations are provided: :func:`el_rhs` integrates (q, q_dot) with the EL matrices (what a
model-based controller believes), :func:`rigid_body_rhs` integrates (q, omega) with Euler's equation
``J omega_dot = -omega x J omega + tau_b`` (the plant used in simulations).
All functions are pure jax.numpy and broadcast over leading axes ``(..., 3)``.
"""

from __future__ import annotations

import jax.numpy as jnp

from formation_ftc.core.constants import SINGULAR_PITCH_LIMIT_RAD, check_away_from_singularity
from formation_ftc.core.quaternion import skew  # S(x) y = x x y, re-exported
from formation_ftc.core.vector3 import matrix3

__all__ = [
    "SINGULAR_PITCH_LIMIT_RAD",
    "skew",
    "rbar",
    "rbar_inv",
    "rbar_inv_dot",
    "inertia_matrix",
    "coriolis_matrix",
    "el_forces",
    "el_rhs",
    "rigid_body_rhs",
    "generalized_to_body_torque",
    "body_to_generalized_force",
    "euler_rates_from_body_rates",
    "body_rates_from_euler_rates",
    "check_away_from_singularity",
]

#: Attitudes with |theta| at or above this are rejected (cos(85 deg) = 0.087: R_bar entries up to ~11.5).


def _mT(a):
    return jnp.swapaxes(a, -1, -2)


def _mv(M, v):
    """M v for stacks of 3x3 matrices, written elementwise (fuses better than batched dots on CPU)."""
    return jnp.sum(M * v[..., None, :], axis=-1)


def _mtv(M, v):
    """M^T v."""
    return jnp.sum(M * v[..., :, None], axis=-2)


def rbar(q):
    """R_bar(q) [-] (..., 3, 3): q_dot = R_bar omega (Mehrabian (27) with rows swapped, E003-08)."""
    th, ph = q[..., 0], q[..., 1]
    ct, st, cp, sp = jnp.cos(th), jnp.sin(th), jnp.cos(ph), jnp.sin(ph)
    tt = st / ct
    z, o = jnp.zeros_like(th), jnp.ones_like(th)
    return matrix3([[z, cp, -sp], [o, sp * tt, cp * tt], [z, sp / ct, cp / ct]])


def rbar_inv(q):
    """W = R_bar^{-1}(q) (..., 3, 3): omega = W q_dot. Finite for every q (rank 2 at theta = +-90 deg)."""
    th, ph = q[..., 0], q[..., 1]
    ct, st, cp, sp = jnp.cos(th), jnp.sin(th), jnp.cos(ph), jnp.sin(ph)
    z, o = jnp.zeros_like(th), jnp.ones_like(th)
    return matrix3([[z, o, -st], [cp, z, sp * ct], [-sp, z, cp * ct]])


def rbar_inv_dot(q, qdot):
    """d/dt R_bar^{-1}(q) along q_dot (..., 3, 3) [1/s]."""
    th, ph = q[..., 0], q[..., 1]
    thd, phd = qdot[..., 0], qdot[..., 1]
    ct, st, cp, sp = jnp.cos(th), jnp.sin(th), jnp.cos(ph), jnp.sin(ph)
    z = jnp.zeros_like(th)
    return matrix3(
        [
            [z, z, -ct * thd],
            [-sp * phd, z, cp * ct * phd - sp * st * thd],
            [-cp * phd, z, -sp * ct * phd - cp * st * thd],
        ]
    )


def inertia_matrix(q, J):
    """D(q) = R_bar^{-T} J R_bar^{-1} [kg m^2] (27); J (..., 3, 3)."""
    W = rbar_inv(q)
    return _mT(W) @ J @ W


def coriolis_matrix(q, qdot, J):
    """C(q, q_dot) = -R_bar^{-T} S(J R_bar^{-1} q_dot) R_bar^{-1} + R_bar^{-T} J d/dt(R_bar^{-1}) (28)."""
    W = rbar_inv(q)
    Wd = rbar_inv_dot(q, qdot)
    omega = (W @ qdot[..., None])[..., 0]
    h = (J @ omega[..., None])[..., 0]
    return -_mT(W) @ skew(h) @ W + _mT(W) @ J @ Wd


def el_forces(q, qdot, acc, vel, J):
    """D(q) acc + C(q, q_dot) vel [N m] without forming D or C (matrix-vector products only)::

        D a + C v = W^T [ J W a - (J W q_dot) x (W v) + J W_dot v ],   W = R_bar^{-1}

    This is the model part of a computed-torque law, e.g. Mehrabian (6): D r_dot + C r.
    """
    W = rbar_inv(q)
    h = _mv(J, _mv(W, qdot))
    inner = (
        _mv(J, _mv(W, acc)) - jnp.cross(h, _mv(W, vel)) + _mv(J, _mv(rbar_inv_dot(q, qdot), vel))
    )
    return _mtv(W, inner)


def el_rhs(q, qdot, u, J):
    """q_ddot = D^{-1}(u - C q_dot) [rad/s^2] for generalised force u [N m] (1) with g = 0."""
    D = inertia_matrix(q, J)
    C = coriolis_matrix(q, qdot, J)
    rhs = u - (C @ qdot[..., None])[..., 0]
    return jnp.linalg.solve(D, rhs[..., None])[..., 0]


def generalized_to_body_torque(q, u):
    """tau_b = R_bar^T u [N m] (body frame) for generalised force u."""
    return _mtv(rbar(q), u)


def body_to_generalized_force(q, tau_b):
    """u = R_bar^{-T} tau_b [N m]."""
    return _mtv(rbar_inv(q), tau_b)


def euler_rates_from_body_rates(q, omega):
    """q_dot = R_bar omega [rad/s]."""
    return _mv(rbar(q), omega)


def body_rates_from_euler_rates(q, qdot):
    """omega = R_bar^{-1} q_dot [rad/s]."""
    return _mv(rbar_inv(q), qdot)


def rigid_body_rhs(q, omega, u, J, J_inv=None):
    """Rigid-body plant in (q, omega): returns (q_dot, omega_dot).

    ``J omega_dot = -omega x (J omega) + R_bar^T u`` (Euler's equation with the body torque of the
    generalised force u [N m]); q_dot = R_bar omega.
    """
    if J_inv is None:
        J_inv = jnp.linalg.inv(J)
    tau_b = generalized_to_body_torque(q, u)
    h = _mv(J, omega)
    omega_dot = _mv(J_inv, jnp.cross(h, omega) + tau_b)
    return euler_rates_from_body_rates(q, omega), omega_dot
