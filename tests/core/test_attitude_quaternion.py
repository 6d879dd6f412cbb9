"""Rigid-body attitude with quaternions (Yang2013 eq. (4)).

Truths: |q| = 1 preserved (the kinematics are norm-preserving; RK4 drift only), torque-free invariants
(kinetic energy, angular momentum in the reference frame), the torque-free axisymmetric closed form
(body rate precesses at lambda = (J3 - J1)/J1 omega3), and the planar gravity-gradient closed form
tau_z = 3 mu / r^3 (J2 - J1) sin(th) cos(th).
"""

import jax
import jax.numpy as jnp
import numpy as np

import formation_ftc  # noqa: F401  (x64)
from formation_ftc.core.dynamics.attitude_quaternion import (
    angular_momentum_reference,
    attitude_rhs,
    gravity_gradient_torque,
    rotational_kinetic_energy,
)
from formation_ftc.core.integrators import rk4_step
from formation_ftc.core.orbit import MU_EARTH
from formation_ftc.core.quaternion import quat_normalize


def propagate(s0, J, dt, n, torque=None, R_body=None):
    def body(s, k):
        s = rk4_step(lambda t, x: attitude_rhs(t, x, J, torque, None, R_body), k * dt, s, dt)
        return s, s

    _, traj = jax.lax.scan(body, jnp.asarray(s0), jnp.arange(n))
    return np.asarray(traj)


def test_torque_free_tumbling_preserves_norm_energy_and_momentum():
    J = jnp.diag(jnp.array([25.0, 30.0, 18.0]))
    q0 = quat_normalize(jnp.array([0.1, -0.3, 0.2, 0.9]))
    s0 = jnp.concatenate([jnp.array([0.05, -0.2, 0.3]), q0])
    traj = propagate(s0, J, 0.01, 20000)  # 200 s, several tumbling periods
    qn = np.linalg.norm(traj[:, 3:], axis=1)
    assert np.max(np.abs(qn - 1.0)) < 1e-9  # invariant: quaternion norm
    T0 = float(rotational_kinetic_energy(s0, J))
    H0 = np.asarray(angular_momentum_reference(s0, J))
    assert np.max(np.abs(np.asarray(rotational_kinetic_energy(traj, J)) - T0)) < 1e-9 * T0
    assert np.max(
        np.linalg.norm(np.asarray(angular_momentum_reference(traj, J)) - H0, axis=1)
    ) < 1e-8 * np.linalg.norm(H0)


def test_axisymmetric_precession_closed_form():
    J1, J3 = 25.0, 40.0
    J = jnp.diag(jnp.array([J1, J1, J3]))
    w0 = np.array([0.1, 0.0, 0.5])
    s0 = jnp.concatenate([jnp.asarray(w0), jnp.array([0.0, 0.0, 0.0, 1.0])])
    dt, n = 0.01, 5000
    traj = propagate(s0, J, dt, n)
    t = dt * np.arange(1, n + 1)
    lam = (J3 - J1) / J1 * w0[2]
    # Euler: w1_dot = -lam w2, w2_dot = lam w1
    truth = np.stack(
        [w0[0] * np.cos(lam * t), w0[0] * np.sin(lam * t), np.full_like(t, w0[2])], axis=1
    )
    np.testing.assert_allclose(traj[:, :3], truth, atol=1e-9)


def test_gravity_gradient_planar_closed_form_and_principal_axis():
    J = jnp.diag(jnp.array([20.0, 25.0, 30.0]))
    r = 7.0e6
    th = 0.3
    R = jnp.array([r * np.cos(th), r * np.sin(th), 0.0])
    tau = gravity_gradient_torque(R, J)
    expected_z = 3 * MU_EARTH / r**3 * (25.0 - 20.0) * np.sin(th) * np.cos(th)
    np.testing.assert_allclose(tau, [0.0, 0.0, expected_z], rtol=1e-12, atol=1e-20)
    np.testing.assert_allclose(
        gravity_gradient_torque(jnp.array([0.0, r, 0.0]), J), 0.0, atol=1e-20
    )


def test_gravity_gradient_and_control_torque_keep_norm_and_add_linearly():
    J = jnp.diag(jnp.array([25.0, 25.0, 25.0])) + 0.5 * (jnp.ones((3, 3)) - jnp.eye(3))
    s = jnp.concatenate(
        [jnp.array([0.01, 0.02, -0.01]), quat_normalize(jnp.array([0.2, 0.1, 0.0, 1.0]))]
    )
    R_body = jnp.array([6.9e6, 1.0e5, 2.0e5])
    tau = jnp.array([0.1, -0.2, 0.05])
    iota = jnp.array([0.02, 0.0, -0.08])
    a = attitude_rhs(0.0, s, J, tau, iota, R_body)
    b = attitude_rhs(0.0, s, J, None, None, R_body)
    np.testing.assert_allclose(J @ (a[:3] - b[:3]), tau + iota, rtol=1e-10, atol=1e-16)
    # spin-up to ~1.6 rad/s in 200 s: the norm drift is pure RK4 truncation error, so it must be small
    # and shrink at (at least) 4th order when the step is halved (continuous flow preserves |q|)
    drift = []
    for dt, n in ((0.05, 4000), (0.025, 8000)):
        traj = propagate(s, J, dt, n, torque=tau, R_body=R_body)
        drift.append(np.max(np.abs(np.linalg.norm(traj[:, 3:], axis=1) - 1.0)))
    assert drift[0] < 1e-7
    assert drift[0] / drift[1] > 12.0, drift
