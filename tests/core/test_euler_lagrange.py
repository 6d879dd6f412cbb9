"""Tests of the Euler-angle EL attitude model (Mehrabian (27)-(28), SPEC P3.2, P3.6-5).

Truths used:
* an independent quaternion / body-rate rigid-body propagation (scipy solve_ivp DOP853 at rtol = atol
  = 1e-12) of the same body torques, converted to Z-Y-X Euler angles with
  scipy.spatial.transform.Rotation;
* the passivity structure D_dot - 2C skew-symmetric (finite-difference D_dot and exact jacfwd);
* algebraic identities R_bar R_bar^{-1} = I and D = D^T > 0.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

import formation_ftc  # noqa: F401  (x64)
from formation_ftc.core.dynamics import euler_lagrange as el
from formation_ftc.core.integrators import rk4_step

J_TEST = np.array([[20.0, 0.4, -0.3], [0.4, 18.0, 0.2], [-0.3, 0.2, 15.0]])


def torque_body(t):
    """Smooth body torque [N m] used by both propagations."""
    return np.array(
        [0.005 * np.sin(0.05 * t), 0.003 * np.sin(0.07 * t), 0.004 * np.sin(0.03 * t + 1.0)]
    )


def torque_body_jax(t):
    return jnp.stack(
        [0.005 * jnp.sin(0.05 * t), 0.003 * jnp.sin(0.07 * t), 0.004 * jnp.sin(0.03 * t + 1.0)]
    )


def quat_mul(p, q):
    """Hamilton product, scalar-last [x, y, z, w]."""
    px, py, pz, pw = p
    qx, qy, qz, qw = q
    return np.array(
        [
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
            pw * qw - px * qx - py * qy - pz * qz,
        ]
    )


def truth_rhs(t, y):
    """Quaternion (body -> inertial, scalar last) and body rate; q_dot = 1/2 q (x) [omega, 0]."""
    quat, w = y[:4], y[4:]
    qd = 0.5 * quat_mul(quat, np.array([w[0], w[1], w[2], 0.0]))
    wd = np.linalg.solve(J_TEST, np.cross(J_TEST @ w, w) + torque_body(t))
    return np.concatenate([qd, wd])


def euler_from_rotation(rot):
    """[theta, phi, psi] from a Rotation (body -> inertial = Rz(psi) Ry(theta) Rx(phi))."""
    psi, theta, phi = rot.as_euler("ZYX").T
    return np.stack([theta, phi, psi], axis=-1)


def wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


Q0 = np.array([0.4, 0.2, 0.3])  # theta, phi, psi [rad]
W0 = np.array([0.002, -0.003, 0.004])  # body rates [rad/s]
T_END, DT, EVERY = 300.0, 0.01, 100


@pytest.fixture(scope="module")
def truth():
    rot0 = Rotation.from_euler("ZYX", [Q0[2], Q0[0], Q0[1]])
    y0 = np.concatenate([rot0.as_quat(), W0])
    t_eval = np.arange(0.0, T_END + 1e-9, DT * EVERY)
    sol = solve_ivp(
        truth_rhs, (0.0, T_END), y0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=t_eval
    )
    assert sol.success
    quat = sol.y[:4].T
    q = euler_from_rotation(Rotation.from_quat(quat / np.linalg.norm(quat, axis=1, keepdims=True)))
    return t_eval, q, sol.y[4:].T


def _scan(step, x0, n_steps):
    def outer(x, k0):
        def inner(x, k):
            return step(k, x), None

        x, _ = jax.lax.scan(inner, x, k0 + jnp.arange(EVERY))
        return x, x

    ks = jnp.arange(n_steps // EVERY) * EVERY
    _, xs = jax.jit(lambda x: jax.lax.scan(outer, x, ks))(x0)
    return jax.tree_util.tree_map(
        lambda a0, a: np.concatenate([np.asarray(a0)[None], np.asarray(a)]), x0, xs
    )


def test_el_form_matches_quaternion_truth(truth):
    """EL form D q_ddot + C q_dot = R_bar^-T tau_b, RK4 dt = 10 ms, vs quaternion truth over 300 s.

    Tolerance 1e-8 rad (issue 6): RK4 global error ~ dt^4 * |d5q| * T is ~1e-10 rad here; the
    remaining budget covers the truth's 1e-12 tolerances and the Euler conversion round-off.
    The motion stays far from the singularity (asserted: max |theta| < 70 deg).
    """
    t_ref, q_ref, _ = truth
    J = jnp.asarray(J_TEST)

    def rhs(t, x):
        q, qd = x
        u = el.body_to_generalized_force(q, torque_body_jax(t))
        return qd, el.el_rhs(q, qd, u, J)

    x0 = (jnp.asarray(Q0), el.euler_rates_from_body_rates(jnp.asarray(Q0), jnp.asarray(W0)))
    qs, _ = _scan(lambda k, x: rk4_step(rhs, k * DT, x, DT), x0, round(T_END / DT))
    assert np.max(np.abs(qs[:, 0])) < np.deg2rad(70)
    err = np.max(np.abs(wrap(qs - q_ref)))
    assert np.max(np.abs(q_ref[:, 2] - q_ref[0, 2])) > 0.5, "the test motion should be large"
    assert err < 1e-8, err


def test_rigid_body_plant_matches_quaternion_truth(truth):
    """The (q, omega) plant used in simulations (tau_b = R_bar^T u) vs the same truth, 1e-8 rad."""
    t_ref, q_ref, w_ref = truth
    J = jnp.asarray(J_TEST)
    Ji = jnp.linalg.inv(J)

    def rhs(t, x):
        q, w = x
        u = el.body_to_generalized_force(q, torque_body_jax(t))
        return el.rigid_body_rhs(q, w, u, J, Ji)

    qs, ws = _scan(
        lambda k, x: rk4_step(rhs, k * DT, x, DT),
        (jnp.asarray(Q0), jnp.asarray(W0)),
        round(T_END / DT),
    )
    assert np.max(np.abs(wrap(qs - q_ref))) < 1e-8
    assert np.max(np.abs(ws - w_ref)) < 1e-9


def _random_states(n=100, seed=0):
    rng = np.random.default_rng(seed)
    q = rng.uniform(-np.pi, np.pi, (n, 3))
    q[:, 0] = rng.uniform(-1.2, 1.2, n)
    qd = rng.normal(0.0, 0.5, (n, 3))
    return q, qd


def test_ddot_minus_2c_is_skew_symmetric():
    """SPEC P3.6-5: 100 random (q, q_dot), |theta| < 1.2 rad: |sym(D_dot - 2C)| < 1e-6 with a central
    finite-difference D_dot (h = 1e-6: truncation ~h^2 |D'''| ~ 1e-10, round-off ~1e-16 |D|/h ~ 1e-9),
    and < 1e-12 with the exact forward-mode derivative."""
    q, qd = _random_states()
    J = jnp.asarray(J_TEST)
    h = 1e-6
    worst_fd, worst_ad = 0.0, 0.0
    for qi, qdi in zip(q, qd, strict=True):
        qi, qdi = jnp.asarray(qi), jnp.asarray(qdi)
        Dd_fd = (el.inertia_matrix(qi + h * qdi, J) - el.inertia_matrix(qi - h * qdi, J)) / (2 * h)
        Dd_ad = jax.jvp(lambda x: el.inertia_matrix(x, J), (qi,), (qdi,))[1]
        C = el.coriolis_matrix(qi, qdi, J)
        for Dd, name in ((Dd_fd, "fd"), (Dd_ad, "ad")):
            N = np.asarray(Dd - 2 * C)
            s = np.max(np.abs(N + N.T)) / 2
            if name == "fd":
                worst_fd = max(worst_fd, s)
            else:
                worst_ad = max(worst_ad, s)
    assert worst_fd < 1e-6
    assert worst_ad < 1e-12


def test_c_qdot_matches_lagrangian_coriolis_terms():
    """C q_dot equals the Lagrangian Coriolis/centrifugal vector D_dot q_dot - d/dq(1/2 q_dot^T D q_dot)
    (independent of the (28) factorisation), to 1e-12 (float64 round-off on O(10) entries)."""
    q, qd = _random_states(20, seed=1)
    J = jnp.asarray(J_TEST)
    for qi, qdi in zip(q, qd, strict=True):
        qi, qdi = jnp.asarray(qi), jnp.asarray(qdi)
        Dd = jax.jvp(lambda x: el.inertia_matrix(x, J), (qi,), (qdi,))[1]
        grad = jax.grad(lambda x, v=qdi: 0.5 * v @ el.inertia_matrix(x, J) @ v)(qi)
        lhs = el.coriolis_matrix(qi, qdi, J) @ qdi
        np.testing.assert_allclose(np.asarray(lhs), np.asarray(Dd @ qdi - grad), atol=1e-12)


def test_identities_and_positive_definiteness():
    q, qd = _random_states(50, seed=2)
    J = jnp.asarray(J_TEST)
    R = el.rbar(jnp.asarray(q))
    W = el.rbar_inv(jnp.asarray(q))
    np.testing.assert_allclose(np.asarray(R @ W), np.broadcast_to(np.eye(3), R.shape), atol=1e-12)
    D = np.asarray(el.inertia_matrix(jnp.asarray(q), J))
    np.testing.assert_allclose(D, np.swapaxes(D, -1, -2), atol=1e-12)
    assert np.all(np.linalg.eigvalsh(D) > 0)
    # the kinematics match scipy's Z-Y-X Euler angles: finite-difference of the rotation gives omega
    h = 1e-6
    qi = q[0]
    w = np.array([0.3, -0.2, 0.1])
    qdot = np.asarray(el.euler_rates_from_body_rates(jnp.asarray(qi), jnp.asarray(w)))
    r0 = Rotation.from_euler("ZYX", [qi[2], qi[0], qi[1]])
    r1 = Rotation.from_euler("ZYX", [qi[2] + h * qdot[2], qi[0] + h * qdot[0], qi[1] + h * qdot[1]])
    w_fd = (r0.inv() * r1).as_rotvec() / h  # body-frame rotation over h
    np.testing.assert_allclose(w_fd, w, atol=1e-6)


def test_singular_attitude_is_rejected():
    el.check_away_from_singularity(np.deg2rad([[60.0, 10.0, 5.0]]))
    with pytest.raises(ValueError, match="singular at theta = \\+-90 deg"):
        el.check_away_from_singularity(
            np.deg2rad([[10.0, 0.0, 0.0], [90.0, 0.0, 0.0]]), field="initial"
        )
    # D really loses rank there
    D = np.asarray(el.inertia_matrix(jnp.asarray([np.pi / 2, 0.3, 0.1]), jnp.asarray(J_TEST)))
    assert np.min(np.abs(np.linalg.eigvalsh(D))) < 1e-12


def test_el_forces_equals_matrix_form():
    """The matrix-free D a + C v used by the controller equals the explicit (27)-(28) matrices (1e-12)."""
    q, qd = _random_states(30, seed=3)
    rng = np.random.default_rng(4)
    a, v = rng.normal(size=(30, 3)), rng.normal(size=(30, 3))
    J = jnp.asarray(J_TEST)
    got = el.el_forces(jnp.asarray(q), jnp.asarray(qd), jnp.asarray(a), jnp.asarray(v), J)
    D = el.inertia_matrix(jnp.asarray(q), J)
    C = el.coriolis_matrix(jnp.asarray(q), jnp.asarray(qd), J)
    want = (D @ jnp.asarray(a)[..., None])[..., 0] + (C @ jnp.asarray(v)[..., None])[..., 0]
    np.testing.assert_allclose(
        np.asarray(got), np.asarray(want), atol=1e-12 * float(np.abs(want).max())
    )
