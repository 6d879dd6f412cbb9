"""Unit quaternions, vector-first and scalar-last ``q = [q1, q2, q3, q4]`` as in Yang2013 eq. (4).

Conventions (all functions broadcast over leading axes, shape ``(..., 4)``):

* product :func:`quat_multiply` is the Hamilton product written vector-first:
  ``p (x) q = [p4 q_v + q4 p_v + p_v x q_v,  p4 q4 - p_v . q_v]``;
* kinematics :func:`quat_kinematics` is Yang2013 eq. (4) (Wie, *Space Vehicle Dynamics and Control*):
  ``q_v_dot = 1/2 (q4 omega - omega x q_v)``, ``q4_dot = -1/2 omega^T q_v``, which equals
  ``1/2 q (x) [omega, 0]`` with the body angular velocity ``omega`` [rad/s];
* :func:`rotation_matrix` is the matrix printed under Yang2013 eq. (5),
  ``C = (q4^2 - q_v^T q_v) I + 2 q_v q_v^T + 2 q4 q_v^x``. Together with the kinematics above it maps
  body-frame components to reference-frame components (``v_ref = C v_body``; ``C_dot = C omega^x``).
  Its transpose :func:`dcm_body_from_reference` maps reference to body components. (The paper calls
  this matrix ``C_i^0``; with its own kinematics it is ``C_0^i`` -- a notation slip with no effect on
  the error-level simulation, where only relative quantities appear.)
* the cross-product matrix :func:`skew` is Yang2013 eq. (3).
"""

from __future__ import annotations

import jax.numpy as jnp

from formation_ftc.core.vector3 import matrix3

__all__ = [
    "skew",
    "quat_multiply",
    "quat_conjugate",
    "quat_normalize",
    "quat_identity",
    "quat_kinematics",
    "rotation_matrix",
    "dcm_body_from_reference",
    "rotate_vector",
    "quat_from_axis_angle",
]


def skew(a):
    """Cross-product matrix ``a^x`` of Yang2013 eq. (3), shape (..., 3) -> (..., 3, 3)."""
    a = jnp.asarray(a)
    z = jnp.zeros_like(a[..., 0])
    a1, a2, a3 = a[..., 0], a[..., 1], a[..., 2]
    return matrix3([[z, -a3, a2], [a3, z, -a1], [-a2, a1, z]])


def quat_multiply(p, q):
    """Hamilton product ``p (x) q`` of vector-first, scalar-last quaternions, shape (..., 4)."""
    p, q = jnp.asarray(p), jnp.asarray(q)
    pv, p4 = p[..., :3], p[..., 3:4]
    qv, q4 = q[..., :3], q[..., 3:4]
    vec = p4 * qv + q4 * pv + jnp.cross(pv, qv)
    sca = p4 * q4 - jnp.sum(pv * qv, axis=-1, keepdims=True)
    return jnp.concatenate([vec, sca], axis=-1)


def quat_conjugate(q):
    """Conjugate ``[-q_v, q4]`` (the inverse of a unit quaternion)."""
    q = jnp.asarray(q)
    return jnp.concatenate([-q[..., :3], q[..., 3:4]], axis=-1)


def quat_normalize(q):
    """``q / |q|``."""
    q = jnp.asarray(q)
    return q / jnp.linalg.norm(q, axis=-1, keepdims=True)


def quat_identity(shape: tuple[int, ...] = ()):
    """Identity quaternion ``[0, 0, 0, 1]`` with leading shape ``shape``."""
    return jnp.broadcast_to(jnp.array([0.0, 0.0, 0.0, 1.0]), (*shape, 4))


def quat_kinematics(q, omega):
    """Quaternion rate of Yang2013 eq. (4) [1/s].

    Parameters
    ----------
    q : (..., 4) quaternion [q_v, q4] [-]
    omega : (..., 3) body angular velocity [rad/s]

    Returns
    -------
    (..., 4) ``[1/2 (q4 omega - omega x q_v), -1/2 omega^T q_v]``  # Yang2013 eq. (4)
    """
    q, omega = jnp.asarray(q), jnp.asarray(omega)
    qv, q4 = q[..., :3], q[..., 3:4]
    vec = 0.5 * (q4 * omega - jnp.cross(omega, qv))
    sca = -0.5 * jnp.sum(omega * qv, axis=-1, keepdims=True)
    return jnp.concatenate([vec, sca], axis=-1)


def rotation_matrix(q):
    """``C = (q4^2 - q_v^T q_v) I + 2 q_v q_v^T + 2 q4 q_v^x`` (Yang2013, under eq. (5)), (..., 3, 3).

    Maps body components to reference components for the kinematics of :func:`quat_kinematics`.
    """
    q = jnp.asarray(q)
    qv, q4 = q[..., :3], q[..., 3]
    eye = jnp.eye(3, dtype=q.dtype)
    return (
        (q4**2 - jnp.sum(qv * qv, axis=-1))[..., None, None] * eye
        + 2.0 * qv[..., :, None] * qv[..., None, :]
        + 2.0 * q4[..., None, None] * skew(qv)
    )


def dcm_body_from_reference(q):
    """Transpose of :func:`rotation_matrix`: reference-frame components -> body components."""
    return jnp.swapaxes(rotation_matrix(q), -1, -2)


def rotate_vector(q, v):
    """``q (x) [v, 0] (x) q*`` (vector part) -- equals ``rotation_matrix(q) @ v`` for a unit q."""
    v = jnp.asarray(v)
    vq = jnp.concatenate([v, jnp.zeros_like(v[..., :1])], axis=-1)
    return quat_multiply(quat_multiply(q, vq), quat_conjugate(q))[..., :3]


def quat_from_axis_angle(axis, angle):
    """Unit quaternion ``[sin(angle/2) axis/|axis|, cos(angle/2)]`` (angle in rad)."""
    axis, angle = jnp.asarray(axis), jnp.asarray(angle)
    n = axis / jnp.linalg.norm(axis, axis=-1, keepdims=True)
    half = 0.5 * angle[..., None]
    return jnp.concatenate([jnp.sin(half) * n, jnp.cos(half)], axis=-1)
