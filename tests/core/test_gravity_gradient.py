"""Gravity-gradient torque on a circular orbit, the LVLH frames and the libration formulas.

Truths: hand-computed torques for a body pitched about the orbit normal and rolled about the
along-track axis; agreement with the independent position-vector form ``3 mu / |R|^5 R x J R`` of
:mod:`formation_ftc.core.dynamics.attitude_quaternion` and with a numpy implementation for random
attitudes and full (non-diagonal) inertias; the LVLH axes from the position and velocity of the orbit;
the closed-form libration frequencies at limits where they are known independently.
"""

import math

import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc  # noqa: F401  (x64)
from formation_ftc.core.dynamics.attitude_quaternion import gravity_gradient_torque
from formation_ftc.core.dynamics.gravity_gradient import (
    attitude_relative_to_lvlh,
    circular_orbit_position,
    gravity_gradient_torque_circular,
    lvlh_to_inertial,
    orbit_rate,
    pitch_libration_frequency,
    quaternion_lvlh_to_inertial,
    radial_unit_in_body,
    roll_yaw_libration_frequencies,
)
from formation_ftc.core.orbit import MU_EARTH
from formation_ftc.core.quaternion import quat_from_axis_angle, rotation_matrix

A = 7.0e6  # orbit radius [m]
N = math.sqrt(MU_EARTH / A**3)


def _dcm_numpy(p):
    """Body -> reference DCM of a vector-first unit quaternion, element by element."""
    x, y, z, w = p / np.linalg.norm(p)
    return np.array(
        [
            [w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z],
        ]
    )


def _random_inertia(rng):
    R, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return R @ np.diag(rng.uniform(10.0, 40.0, 3)) @ R.T


def test_orbit_rate_and_position():
    assert float(orbit_rate(A)) == pytest.approx(1.0780e-3, rel=1e-4)  # 2 pi / n = 97.1 min
    assert 2 * math.pi / float(orbit_rate(A)) / 60.0 == pytest.approx(97.14, abs=0.01)
    r = np.asarray(circular_orbit_position(np.array([0.0, 0.25 * 2 * math.pi / N]), A))
    np.testing.assert_allclose(r, [[A, 0, 0], [0, A, 0]], atol=1e-6)


def test_pitch_torque_hand_computed():
    """Body pitched by +30 deg about the orbit normal from LVLH (u = 0): r_b = [cos th, -sin th, 0],
    tau_z = -3 n^2 (J_y - J_x) sin th cos th (restoring when J_y > J_x), tau_x = tau_y = 0."""
    J = np.diag([20.0, 30.0, 25.0])
    th = math.radians(30.0)
    q = quat_from_axis_angle(jnp.array([0.0, 0.0, 1.0]), jnp.asarray(th))
    tau = np.asarray(gravity_gradient_torque_circular(0.0, q, J, A))
    expected_z = (
        -3.0 * N**2 * (30.0 - 20.0) * math.sin(th) * math.cos(th)
    )  # = -3 n^2 * 10 * sqrt(3)/4
    np.testing.assert_allclose(tau, [0.0, 0.0, expected_z], atol=1e-18)
    assert tau[2] < 0.0  # pulls the pitch back towards 0
    np.testing.assert_allclose(
        np.asarray(radial_unit_in_body(q, 0.0)), [math.cos(th), -math.sin(th), 0.0], atol=1e-15
    )


def test_roll_torque_hand_computed():
    """Body rotated by +20 deg about the along-track axis (body y) at u = 90 deg (radial = inertial y,
    along-track = -inertial x): r_b = [cos ph, 0, sin ph], tau_y = 3 n^2 (J_x - J_z) sin ph cos ph."""
    J = np.diag([20.0, 30.0, 25.0])
    ph, u = math.radians(20.0), math.pi / 2
    q_l = quat_from_axis_angle(jnp.array([0.0, 1.0, 0.0]), jnp.asarray(ph))  # body -> LVLH
    q = np.asarray(quaternion_lvlh_to_inertial(jnp.asarray(u)))
    x, y, z, w = q
    qv = np.asarray(q_l)
    # q_IL (x) q_L written out (Hamilton, vector first)
    q_i = np.concatenate(
        [w * qv[:3] + qv[3] * q[:3] + np.cross(q[:3], qv[:3]), [w * qv[3] - q[:3] @ qv[:3]]]
    )
    tau = np.asarray(gravity_gradient_torque_circular(u / N, jnp.asarray(q_i), J, A))
    np.testing.assert_allclose(
        tau, [0.0, 3.0 * N**2 * (20.0 - 25.0) * math.sin(ph) * math.cos(ph), 0.0], atol=1e-18
    )


def test_torque_matches_position_vector_form_and_numpy():
    rng = np.random.default_rng(14)
    for _ in range(20):
        J = _random_inertia(rng)
        p = rng.normal(size=4)
        p /= np.linalg.norm(p)
        t = rng.uniform(0.0, 6000.0)
        u0 = rng.uniform(-math.pi, math.pi)
        tau = np.asarray(gravity_gradient_torque_circular(t, jnp.asarray(p), J, A, u0=u0))
        # independent: R in body axes from a numpy DCM, then 3 mu / |R|^5 R x J R (both implementations)
        u = u0 + N * t
        R_body = _dcm_numpy(p).T @ (A * np.array([math.cos(u), math.sin(u), 0.0]))
        ref = 3.0 * MU_EARTH / A**5 * np.cross(R_body, J @ R_body)
        np.testing.assert_allclose(tau, ref, rtol=1e-10, atol=1e-12 * np.abs(ref).max())
        np.testing.assert_allclose(
            tau,
            np.asarray(gravity_gradient_torque(R_body, J)),
            rtol=1e-10,
            atol=1e-12 * np.abs(ref).max(),
        )
    # batched: per-spacecraft inertia (N, 3, 3) against the loop above
    Js = np.stack([_random_inertia(rng) for _ in range(3)])
    ps = rng.normal(size=(3, 4))
    ps /= np.linalg.norm(ps, axis=1, keepdims=True)
    batched = np.asarray(gravity_gradient_torque_circular(100.0, jnp.asarray(ps), Js, A))
    for k in range(3):
        np.testing.assert_allclose(
            batched[k],
            np.asarray(gravity_gradient_torque_circular(100.0, ps[k], Js[k], A)),
            rtol=1e-12,
        )


def test_zero_torque_when_a_principal_axis_is_radial():
    J = np.diag([20.0, 30.0, 25.0])
    for axis in ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]):
        q = quat_from_axis_angle(
            jnp.asarray(axis), jnp.asarray(math.pi / 2)
        )  # some principal axis -> radial
        assert np.abs(np.asarray(gravity_gradient_torque_circular(0.0, q, J, A))).max() < 1e-20


def test_lvlh_axes_are_radial_along_track_normal():
    for u in (0.3, 2.0, -1.2):
        C = np.asarray(lvlh_to_inertial(u))
        r = np.array([math.cos(u), math.sin(u), 0.0])
        v = np.array([-math.sin(u), math.cos(u), 0.0])  # prograde circular velocity direction
        np.testing.assert_allclose(C[:, 0], r, atol=1e-15)
        np.testing.assert_allclose(C[:, 1], v, atol=1e-15)
        np.testing.assert_allclose(C[:, 2], np.cross(r, v), atol=1e-15)
        np.testing.assert_allclose(
            np.asarray(rotation_matrix(quaternion_lvlh_to_inertial(u))), C, atol=1e-15
        )
        p = np.array([0.2, -0.4, 0.1, 0.88])
        p /= np.linalg.norm(p)
        q_l = np.asarray(attitude_relative_to_lvlh(jnp.asarray(p), u))
        np.testing.assert_allclose(_dcm_numpy(q_l), C.T @ _dcm_numpy(p), atol=1e-14)


def test_libration_formulas():
    # pitch: n sqrt(3 (J_y - J_x) / J_z), unstable (rejected) when the radial inertia exceeds the along-track one
    assert pitch_libration_frequency((10.0, 20.0, 25.0), N) == pytest.approx(
        N * math.sqrt(3 * 10 / 25), rel=1e-15
    )
    with pytest.raises(ValueError, match="J_y"):
        pitch_libration_frequency((20.0, 10.0, 25.0), N)
    # roll/yaw: sum and product of the squared roots (Vieta) for a body in the stable Lagrange region
    # (J_z > J_y > J_x); the simulated frequencies are checked in tests/components/test_attitude_truth_plant.py
    J = (10.0, 20.0, 25.0)
    w1, w2 = roll_yaw_libration_frequencies(J, N)
    kr, ky = (25 - 10) / 20, (25 - 20) / 10
    assert (w1**2 + w2**2) / N**2 == pytest.approx(1 + 3 * kr + kr * ky, rel=1e-13)
    assert (w1**2 * w2**2) / N**4 == pytest.approx(4 * kr * ky, rel=1e-13)
    assert 0 < w1 < w2
    with pytest.raises(ValueError, match="not a libration"):
        roll_yaw_libration_frequencies((25.0, 20.0, 10.0), N)  # radial axis of maximum inertia
