"""Quaternion algebra and kinematics (Yang2013 eq. (3)-(5) conventions): property tests.

Truths: group axioms of the Hamilton product, orthonormality of the rotation matrix, the homomorphism
R(p q) = R(p) R(q), R v = q v q*, and the kinematic identity dR/dt = R omega^x (checked with forward-mode
autodiff along the quaternion ODE). Tolerances 1e-12 (float64 round-off of O(1) quantities).
"""

import jax
import jax.numpy as jnp
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import formation_ftc  # noqa: F401  (x64)
from formation_ftc.core.quaternion import (
    dcm_body_from_reference,
    quat_conjugate,
    quat_from_axis_angle,
    quat_identity,
    quat_kinematics,
    quat_multiply,
    quat_normalize,
    rotate_vector,
    rotation_matrix,
    skew,
)

finite = st.floats(-1.0, 1.0, allow_nan=False, allow_infinity=False)
vec3 = st.tuples(finite, finite, finite).map(np.array)
quat = (
    st.tuples(finite, finite, finite, finite)
    .filter(lambda v: np.linalg.norm(v) > 0.1)
    .map(lambda v: np.array(v) / np.linalg.norm(v))
)

TOL = 1e-12
SETTINGS = settings(max_examples=40, deadline=None)


@SETTINGS
@given(quat, quat, quat)
def test_product_associative_and_norm_multiplicative(p, q, r):
    lhs = quat_multiply(quat_multiply(p, q), r)
    rhs = quat_multiply(p, quat_multiply(q, r))
    np.testing.assert_allclose(lhs, rhs, atol=TOL)
    np.testing.assert_allclose(jnp.linalg.norm(quat_multiply(p, q)), 1.0, atol=TOL)


@SETTINGS
@given(quat)
def test_conjugate_is_inverse_and_identity_neutral(q):
    np.testing.assert_allclose(quat_multiply(q, quat_conjugate(q)), [0, 0, 0, 1], atol=TOL)
    np.testing.assert_allclose(quat_multiply(quat_identity(), q), q, atol=TOL)


@SETTINGS
@given(quat, quat, vec3)
def test_rotation_matrix_homomorphism_and_vector_rotation(p, q, v):
    R = rotation_matrix(q)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=TOL)
    np.testing.assert_allclose(jnp.linalg.det(R), 1.0, atol=TOL)
    np.testing.assert_allclose(
        rotation_matrix(quat_multiply(p, q)), rotation_matrix(p) @ R, atol=TOL
    )
    np.testing.assert_allclose(rotate_vector(q, v), R @ v, atol=TOL)
    np.testing.assert_allclose(dcm_body_from_reference(q) @ (R @ v), v, atol=TOL)
    np.testing.assert_allclose(rotation_matrix(-q), R, atol=TOL)  # double cover


@SETTINGS
@given(quat, vec3)
def test_kinematics_is_half_q_times_omega_and_preserves_norm(q, w):
    qd = quat_kinematics(q, w)
    np.testing.assert_allclose(qd, 0.5 * quat_multiply(q, jnp.append(w, 0.0)), atol=TOL)
    np.testing.assert_allclose(jnp.dot(q, qd), 0.0, atol=TOL)  # d|q|^2/dt = 0


@SETTINGS
@given(quat, vec3)
def test_rotation_matrix_rate_matches_body_angular_velocity(q, w):
    # along q_dot = quat_kinematics(q, w): d/dt C(q) = C omega^x (C maps body -> reference)
    _, Cdot = jax.jvp(rotation_matrix, (jnp.asarray(q),), (quat_kinematics(q, w),))
    np.testing.assert_allclose(Cdot, rotation_matrix(q) @ skew(w), atol=1e-12)


@SETTINGS
@given(vec3, vec3)
def test_skew_is_cross_product(a, b):
    np.testing.assert_allclose(skew(a) @ b, np.cross(a, b), atol=TOL)


def test_axis_angle_and_batching():
    q = quat_from_axis_angle(jnp.array([0.0, 0.0, 1.0]), jnp.pi / 2)
    np.testing.assert_allclose(rotation_matrix(q) @ np.array([1.0, 0, 0]), [0, 1, 0], atol=TOL)
    qs = quat_normalize(jnp.arange(1.0, 13.0).reshape(3, 4))
    Rs = rotation_matrix(qs)
    assert Rs.shape == (3, 3, 3) and Rs.dtype == jnp.float64
    for k in range(3):
        np.testing.assert_allclose(Rs[k], rotation_matrix(qs[k]), atol=TOL)
