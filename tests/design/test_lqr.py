"""LQR on the Clohessy-Wiltshire model (Bryson weights): Riccati residual, closed-loop stability, the
hand-solved double-integrator gain and python-control's ``lqr``."""

import math

import numpy as np
import pytest

from formation_ftc.core.dynamics.cw import cw_matrices
from formation_ftc.core.orbit import MU_EARTH
from formation_ftc.design.lqr import bryson_weights, care_relative_residual, cw_lqr, lqr

N_7000 = math.sqrt(MU_EARTH / 7000e3**3)  # mean motion of a 7,000 km circular orbit [rad/s]
DESIGNS = [
    (N_7000, 10.0, 1.0, 1.0),
    (N_7000, (10.0, 20.0, 40.0), (1.0, 0.5, 2.0), (1.0, 0.1, 0.3)),
    (0.0, 5.0, 0.2, 0.05),
]


def _double_integrator_closed_form(q1, q2, r):
    """1-D double integrator x'' = u, Q = diag(q1, q2), R = r. Writing P = [[p1, p2], [p2, p3]], the
    CARE A^T P + P A - P B r^-1 B^T P + Q = 0 reads, entry by entry,
        (1,1): q1 - p2^2 / r = 0               ->  p2 = sqrt(q1 r)
        (2,2): 2 p2 + q2 - p3^2 / r = 0        ->  p3 = sqrt(r (2 p2 + q2))
        (1,2): p1 - p2 p3 / r = 0              ->  p1 = p2 p3 / r
    (positive roots: P > 0 since p1 p3 - p2^2 = p2^2 + p2 q2 > 0), so K = B^T P / r = [p2, p3] / r =
    [sqrt(q1/r), sqrt(2 sqrt(q1/r) + q2/r)]."""
    p2 = math.sqrt(q1 * r)
    p3 = math.sqrt(r * (2 * p2 + q2))
    P = np.array([[p2 * p3 / r, p2], [p2, p3]])
    K = np.array([math.sqrt(q1 / r), math.sqrt(2 * math.sqrt(q1 / r) + q2 / r)])
    return P, K


@pytest.mark.parametrize("n, pmax, vmax, amax", DESIGNS)
def test_riccati_residual_and_hurwitz(n, pmax, vmax, amax):
    d = cw_lqr(n, pmax, vmax, amax)
    A, B = cw_matrices(n)
    np.testing.assert_array_equal(d.A, A)
    # residual recomputed here: ||A^T P + P A - P B R^-1 B^T P + Q||_F / ||Q||_F <= 1e-10
    res = A.T @ d.P + d.P @ A - d.P @ B @ np.linalg.inv(d.R) @ B.T @ d.P + d.Q
    assert np.linalg.norm(res) <= 1e-10 * np.linalg.norm(d.Q)
    assert d.relative_residual <= 1e-12
    assert d.relative_residual == pytest.approx(care_relative_residual(d.P, A, B, d.Q, d.R))
    np.testing.assert_allclose(d.P, d.P.T, atol=0)
    assert np.min(np.linalg.eigvalsh(d.P)) > 0
    np.testing.assert_allclose(d.K, np.linalg.inv(d.R) @ B.T @ d.P, rtol=1e-12)
    eig = np.linalg.eigvals(A - B @ d.K)
    assert np.max(eig.real) < 0
    np.testing.assert_allclose(
        np.sort_complex(eig), np.sort_complex(d.closed_loop_eigenvalues), rtol=1e-10
    )


def test_bryson_weights():
    Q, R = bryson_weights([10.0, 0.5], [2.0])
    np.testing.assert_allclose(Q, np.diag([0.01, 4.0]))
    np.testing.assert_allclose(R, [[0.25]])


@pytest.mark.parametrize(
    "q1, q2, r", [(1.0, 1.0, 1.0), (0.01, 1.0, 1.0), (3.0, 0.0, 0.2), (1e-4, 25.0, 400.0)]
)
def test_double_integrator_closed_form(q1, q2, r):
    P_exact, K_exact = _double_integrator_closed_form(q1, q2, r)
    d = lqr([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0]], np.diag([q1, q2]), [[r]])
    np.testing.assert_allclose(d.P, P_exact, rtol=1e-10)
    np.testing.assert_allclose(d.K[0], K_exact, rtol=1e-10)


def test_cw_lqr_at_zero_mean_motion_is_three_double_integrators():
    """n = 0: the CW model is three decoupled double integrators; with Bryson's weights per axis the
    gain of axis k is the closed form with q1 = 1/p_max^2, q2 = 1/v_max^2, r = 1/a_max^2."""
    pmax, vmax, amax = (
        np.array([10.0, 20.0, 40.0]),
        np.array([1.0, 0.5, 2.0]),
        np.array([1.0, 0.1, 0.3]),
    )
    d = cw_lqr(0.0, pmax, vmax, amax)
    K = np.zeros((3, 6))
    for k in range(3):
        _, (kp, kd) = _double_integrator_closed_form(
            1 / pmax[k] ** 2, 1 / vmax[k] ** 2, 1 / amax[k] ** 2
        )
        K[k, k], K[k, 3 + k] = kp, kd
    np.testing.assert_allclose(d.K, K, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("n, pmax, vmax, amax", DESIGNS)
def test_gain_equals_python_control(n, pmax, vmax, amax):
    control = pytest.importorskip("control")
    d = cw_lqr(n, pmax, vmax, amax)
    K, S, E = control.lqr(d.A, d.B, d.Q, d.R)
    np.testing.assert_allclose(d.K, np.asarray(K), rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(d.P, np.asarray(S), rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(
        np.sort_complex(d.closed_loop_eigenvalues), np.sort_complex(np.asarray(E)), rtol=1e-8
    )


@pytest.mark.parametrize(
    "kwargs, needle",
    [
        (dict(max_position_error=0.0), "max_position_error"),
        (dict(max_velocity_error=[1.0, 2.0]), "max_velocity_error"),
        (dict(max_acceleration=float("inf")), "max_acceleration"),
        (dict(mean_motion=-1e-3), "mean_motion"),
    ],
)
def test_bad_input(kwargs, needle):
    args = (
        dict(
            mean_motion=N_7000,
            max_position_error=10.0,
            max_velocity_error=1.0,
            max_acceleration=1.0,
        )
        | kwargs
    )
    with pytest.raises(ValueError, match=needle):
        cw_lqr(**args)


def test_cw_lqr_solves_once_per_design_and_shares_read_only_arrays():
    from formation_ftc.design.lqr import cw_lqr

    a = cw_lqr(0.0011, 1.0, [0.1, 0.1, 0.1], 0.01)
    b = cw_lqr(
        0.0011, [1.0, 1.0, 1.0], 0.1, [0.01, 0.01, 0.01]
    )  # the same design written another way
    assert b is a
    assert not a.K.flags.writeable and not a.P.flags.writeable
    c = cw_lqr(0.0011, 2.0, 0.1, 0.01)
    assert c is not a and not np.allclose(c.K, a.K)
