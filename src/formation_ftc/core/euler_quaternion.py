"""Conversions between unit quaternions and Z-Y-X Euler angles, and the Euler-angle torque map.

Conventions, shared with :mod:`formation_ftc.core.quaternion` and
:mod:`formation_ftc.core.dynamics.euler_lagrange`:

* quaternion ``p = [p1, p2, p3, p4]`` (vector first, scalar last), kinematics
  ``p_dot = 1/2 p (x) [omega, 0]`` with the body angular velocity ``omega`` [rad/s]; its matrix
  ``C(p)`` (:func:`~formation_ftc.core.quaternion.rotation_matrix`) maps body components to reference
  components, ``C_dot = C omega^x``;
* Euler angles ``q = [theta, phi, psi]`` (pitch, roll, yaw) [rad] of the **3-2-1 (Z-Y-X) sequence**:
  yaw psi about z, then pitch theta about the new y, then roll phi about the new x, i.e. the
  body-to-reference rotation ``C = Rz(psi) Ry(theta) Rx(phi)``::

      C = [[c_psi c_th,  c_psi s_th s_phi - s_psi c_phi,  c_psi s_th c_phi + s_psi s_phi],
           [s_psi c_th,  s_psi s_th s_phi + c_psi c_phi,  s_psi s_th c_phi - c_psi s_phi],
           [-s_th,       c_th s_phi,                      c_th c_phi                    ]]

  inverted by ``theta = atan2(-C31, sqrt(C32^2 + C33^2))`` in [-pi/2, pi/2],
  ``phi = atan2(C32, C33)``, ``psi = atan2(C21, C11)`` (both in (-pi, pi]);
* the quaternion of ``q`` is ``p = p_z(psi) (x) p_y(theta) (x) p_x(phi)`` (Hamilton products of the
  elementary rotations) -- the same attitude as ``-p``, which maps to the same angles;
* kinematics of the angles: ``q_dot = R_bar(q) omega`` and ``omega = E(q) q_dot`` with
  ``E = R_bar^{-1}`` (:func:`~formation_ftc.core.dynamics.euler_lagrange.rbar`, ``rbar_inv``)::

      E(q) = [[0,      1,  -s_th      ],      R_bar(q) = [[0,  c_phi,         -s_phi        ],
              [c_phi,  0,   s_phi c_th],                  [1,  s_phi t_th,     c_phi t_th   ],
              [-s_phi, 0,   c_phi c_th]]                  [0,  s_phi / c_th,   c_phi / c_th ]]

  ``det E = -cos(theta)``: the representation is **singular at theta = +-90 deg** (gimbal lock:
  phi and psi are not separately defined, R_bar has 1/cos(theta));
* torques: a generalised torque ``tau_gen`` [N m] conjugate to ``q`` does the same work as the body
  torque ``tau_body = E(q)^{-T} tau_gen = R_bar(q)^T tau_gen`` (power
  ``tau_body . omega = tau_gen . q_dot``).

All functions are pure ``jax.numpy`` and broadcast over leading axes.
"""

from __future__ import annotations

import jax.numpy as jnp

from formation_ftc.core.dynamics.euler_lagrange import (
    body_to_generalized_force,
    generalized_to_body_torque,
    rbar,
    rbar_inv,
)
from formation_ftc.core.quaternion import (
    quat_from_axis_angle,
    quat_multiply,
    quat_normalize,
    rotation_matrix,
)
from formation_ftc.core.vector3 import matrix3

__all__ = [
    "dcm_from_euler_zyx",
    "euler_zyx_from_dcm",
    "quaternion_from_euler_zyx",
    "euler_zyx_from_quaternion",
    "euler_rates_zyx",
    "body_rates_zyx",
    "body_torque_from_generalised",
    "generalised_torque_from_body",
]


def dcm_from_euler_zyx(q):
    """``C = Rz(psi) Ry(theta) Rx(phi)`` (body to reference) [-], q = [theta, phi, psi] (..., 3) [rad]."""
    ct, cp, cs = jnp.cos(q[..., 0]), jnp.cos(q[..., 1]), jnp.cos(q[..., 2])  # theta, phi, psi
    st, sp, ss = jnp.sin(q[..., 0]), jnp.sin(q[..., 1]), jnp.sin(q[..., 2])
    return matrix3(
        [
            [cs * ct, cs * st * sp - ss * cp, cs * st * cp + ss * sp],
            [ss * ct, ss * st * sp + cs * cp, ss * st * cp - cs * sp],
            [-st, ct * sp, ct * cp],
        ]
    )


def euler_zyx_from_dcm(C):
    """``[theta, phi, psi]`` [rad] of a body-to-reference rotation matrix ``C`` (..., 3, 3).

    theta in [-pi/2, pi/2], phi and psi in (-pi, pi]; at theta = +-pi/2 only phi -+ psi is defined.
    """
    theta = jnp.arctan2(-C[..., 2, 0], jnp.hypot(C[..., 2, 1], C[..., 2, 2]))
    phi = jnp.arctan2(C[..., 2, 1], C[..., 2, 2])
    psi = jnp.arctan2(C[..., 1, 0], C[..., 0, 0])
    return jnp.stack([theta, phi, psi], -1)


def quaternion_from_euler_zyx(q):
    """Unit quaternion (vector first) of the 3-2-1 angles: ``p_z(psi) (x) p_y(theta) (x) p_x(phi)``."""
    q = jnp.asarray(q)
    shape = q.shape[:-1]

    def axis(k):
        return jnp.broadcast_to(jnp.eye(3)[k], (*shape, 3))

    pz = quat_from_axis_angle(axis(2), q[..., 2])
    py = quat_from_axis_angle(axis(1), q[..., 0])
    px = quat_from_axis_angle(axis(0), q[..., 1])
    return quat_multiply(quat_multiply(pz, py), px)


def euler_zyx_from_quaternion(p):
    """``[theta, phi, psi]`` [rad] of a quaternion (vector first, normalised here first) (..., 4)."""
    return euler_zyx_from_dcm(rotation_matrix(quat_normalize(p)))


def euler_rates_zyx(q, omega):
    """``q_dot = R_bar(q) omega`` [rad/s]: Euler-angle rates from body rates (singular at cos(theta) = 0)."""
    return jnp.sum(rbar(q) * omega[..., None, :], axis=-1)


def body_torque_from_generalised(q, tau_gen):
    """``tau_body = E(q)^{-T} tau_gen = R_bar(q)^T tau_gen`` [N m] (``omega = E(q) q_dot``)."""
    return generalized_to_body_torque(q, tau_gen)


def generalised_torque_from_body(q, tau_body):
    """``tau_gen = E(q)^T tau_body`` [N m], the inverse of :func:`body_torque_from_generalised`."""
    return body_to_generalized_force(q, tau_body)


def body_rates_zyx(q, qdot):
    """``omega = E(q) q_dot`` [rad/s]."""
    return jnp.sum(rbar_inv(q) * qdot[..., None, :], axis=-1)
