"""3-2-1 Euler angles <-> quaternions, the Euler-angle rate map and the generalised / body torque map,
against independent truths: elementary rotation matrices built in numpy, the closed-form attitude under
a constant body rate, finite differences, and the power balance."""

from __future__ import annotations

import jax
import numpy as np
import pytest

from formation_ftc.core.dynamics.euler_lagrange import rbar, rbar_inv
from formation_ftc.core.euler_quaternion import (
    body_rates_zyx,
    body_torque_from_generalised,
    dcm_from_euler_zyx,
    euler_rates_zyx,
    euler_zyx_from_dcm,
    euler_zyx_from_quaternion,
    generalised_torque_from_body,
    quaternion_from_euler_zyx,
)
from formation_ftc.core.quaternion import quat_kinematics, rotation_matrix

RNG = np.random.default_rng(7)


def _angles(n: int, pitch_deg: float = 80.0) -> np.ndarray:
    """[theta, phi, psi] with |theta| < pitch_deg, phi, psi in (-pi, pi)."""
    th = np.deg2rad(RNG.uniform(-pitch_deg, pitch_deg, n))
    ph, ps = RNG.uniform(-np.pi + 1e-6, np.pi - 1e-6, (2, n))
    return np.stack([th, ph, ps], -1)


def _rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def test_dcm_is_rz_ry_rx_and_the_quaternion_rotates_the_same_way():
    q = _angles(50)
    for row, C, Cq in zip(
        q,
        np.asarray(dcm_from_euler_zyx(q)),
        np.asarray(rotation_matrix(quaternion_from_euler_zyx(q))),
        strict=True,
    ):
        th, ph, ps = row
        truth = _rz(ps) @ _ry(th) @ _rx(ph)  # 3-2-1: yaw, then pitch, then roll
        np.testing.assert_allclose(C, truth, atol=1e-14)
        np.testing.assert_allclose(Cq, truth, atol=1e-14)


def test_euler_quaternion_round_trips():
    q = _angles(500)
    np.testing.assert_allclose(
        np.asarray(euler_zyx_from_quaternion(quaternion_from_euler_zyx(q))), q, atol=1e-12
    )
    np.testing.assert_allclose(np.asarray(euler_zyx_from_dcm(dcm_from_euler_zyx(q))), q, atol=1e-12)
    p = RNG.normal(size=(500, 4))
    p /= np.linalg.norm(p, axis=-1, keepdims=True)
    back = np.asarray(quaternion_from_euler_zyx(euler_zyx_from_quaternion(p)))
    sign = np.sign(np.sum(back * p, axis=-1, keepdims=True))  # p and -p are the same attitude
    np.testing.assert_allclose(sign * back, p, atol=1e-12)
    # a non-unit quaternion (RK4 drift) is normalised before the conversion
    np.testing.assert_allclose(
        np.asarray(euler_zyx_from_quaternion(1.001 * p)),
        np.asarray(euler_zyx_from_quaternion(p)),
        atol=1e-14,
    )


def test_euler_rates_match_finite_differences_of_the_exact_attitude_under_a_constant_body_rate():
    """For a constant body rate w, p(t) = p0 (x) [sin(|w| t/2) w/|w|, cos(|w| t/2)] solves
    p_dot = 1/2 p (x) [w, 0] exactly; the central difference of its Euler angles is R_bar(q) w."""
    from formation_ftc.core.quaternion import quat_multiply

    q0 = _angles(40, pitch_deg=70.0)
    w = RNG.normal(scale=0.3, size=(40, 3))
    p0 = np.asarray(quaternion_from_euler_zyx(q0))

    def p_at(t):
        a = np.linalg.norm(w, axis=-1, keepdims=True)
        return np.asarray(
            quat_multiply(
                p0, np.concatenate([np.sin(0.5 * a * t) * w / a, np.cos(0.5 * a * t)], -1)
            )
        )

    # the closed form solves the plant's kinematics (checked by its own finite difference)
    h = 1e-5
    np.testing.assert_allclose(
        (p_at(h) - p_at(-h)) / (2 * h), np.asarray(quat_kinematics(p0, w)), atol=1e-9
    )
    fd = (
        np.asarray(euler_zyx_from_quaternion(p_at(h)))
        - np.asarray(euler_zyx_from_quaternion(p_at(-h)))
    ) / (2 * h)
    np.testing.assert_allclose(np.asarray(euler_rates_zyx(q0, w)), fd, rtol=1e-7, atol=1e-8)
    # and omega = E(q) q_dot inverts it
    np.testing.assert_allclose(np.asarray(body_rates_zyx(q0, fd)), w, atol=1e-7)


def test_euler_rates_are_the_exact_derivative_of_the_conversion():
    """Forward-mode derivative of euler(p) along the quaternion kinematics equals R_bar(q) w (no step)."""
    q = _angles(30)
    w = RNG.normal(size=(30, 3))
    p = quaternion_from_euler_zyx(q)
    _, qdot = jax.jvp(euler_zyx_from_quaternion, (p,), (quat_kinematics(p, w),))
    np.testing.assert_allclose(
        np.asarray(qdot), np.asarray(euler_rates_zyx(q, w)), rtol=1e-10, atol=1e-12
    )


def test_kinematic_matrix_and_its_singularity():
    q = _angles(20)
    th, ph = q[:, 0], q[:, 1]
    E = np.asarray(rbar_inv(q))
    for k in range(20):  # E(q) as written in formation_ftc.core.euler_quaternion
        st, ct, sp, cp = np.sin(th[k]), np.cos(th[k]), np.sin(ph[k]), np.cos(ph[k])
        np.testing.assert_allclose(
            E[k], [[0, 1, -st], [cp, 0, sp * ct], [-sp, 0, cp * ct]], atol=1e-15
        )
    np.testing.assert_allclose(
        np.linalg.det(E), -np.cos(th), atol=1e-14
    )  # singular at theta = +-90 deg
    np.testing.assert_allclose(
        np.asarray(rbar(q)) @ E, np.broadcast_to(np.eye(3), E.shape), atol=1e-12
    )
    near = np.array([[np.deg2rad(89.999), 0.3, 0.2]])
    assert np.abs(np.asarray(rbar(near))).max() > 1e4  # R_bar blows up next to gimbal lock


@pytest.mark.parametrize("pitch_deg", [10.0, 60.0, 85.0])
def test_torque_map_conserves_power(pitch_deg):
    """tau_body . omega == tau_gen . q_dot with tau_body = E^-T tau_gen, omega = E q_dot."""
    q = _angles(200, pitch_deg)
    qdot = RNG.normal(size=(200, 3))
    tau_gen = RNG.normal(size=(200, 3))
    omega = np.asarray(body_rates_zyx(q, qdot))
    tau_body = np.asarray(body_torque_from_generalised(q, tau_gen))
    np.testing.assert_allclose(
        np.sum(tau_body * omega, -1), np.sum(tau_gen * qdot, -1), rtol=1e-10, atol=1e-12
    )
    # independent: solve E^T tau_body = tau_gen with numpy
    E = np.asarray(rbar_inv(q))
    np.testing.assert_allclose(
        tau_body,
        np.linalg.solve(np.swapaxes(E, -1, -2), tau_gen[..., None])[..., 0],
        rtol=1e-9,
        atol=1e-9,
    )
    np.testing.assert_allclose(
        np.asarray(generalised_torque_from_body(q, tau_body)), tau_gen, atol=1e-9
    )
