"""Kalman design (formation_ftc.design.kalman) against independent oracles: the process-noise integral by
adaptive quadrature, the random walk's closed-form steady state, and the Riccati fixed point reached by
iterating the filter's own covariance recursion."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg

from formation_ftc.core.dynamics.cw import cw_matrices
from formation_ftc.design.kalman import dare_relative_residual, discrete_model, steady_state_kalman

N_LEO = math.sqrt(3.986004418e14 / 7000e3**3)


def test_process_noise_matches_quadrature_of_its_definition():
    A, B = cw_matrices(N_LEO)
    q, dt = 3e-9, 5.0
    m = discrete_model(A, B, B, q, dt)

    def integrand(s):
        e = scipy.linalg.expm(A * s)
        return e @ B @ (q * B.T) @ e.T

    ref, _ = scipy.integrate.quad_vec(integrand, 0.0, dt, epsabs=0.0, epsrel=1e-12)
    np.testing.assert_allclose(m.qd, ref, rtol=1e-9, atol=1e-25)
    np.testing.assert_allclose(m.phi, scipy.linalg.expm(A * dt), rtol=1e-12, atol=1e-15)


def test_random_walk_closed_form():
    # x_{k+1} = x_k + w (var q), y = x + v (var r): P = (q + sqrt(q^2 + 4 q r)) / 2, K = P / (P + r)
    q, r = 0.3, 2.0
    P, K = steady_state_kalman([[1.0]], [[q]], [[r]])
    p = (q + math.sqrt(q * q + 4 * q * r)) / 2
    assert P[0, 0] == pytest.approx(p, rel=1e-12)
    assert K[0, 0] == pytest.approx(p / (p + r), rel=1e-12)


def test_cw_filter_riccati_is_the_limit_of_the_covariance_recursion():
    A, B = cw_matrices(N_LEO)
    m = discrete_model(A, B, B, 1e-10, 0.5)
    R = np.diag([0.1**2] * 3 + [1e-3**2] * 3)
    P, K = steady_state_kalman(m.phi, m.qd, R)
    assert dare_relative_residual(P, m.phi, m.qd, R) < 1e-10
    # iterate predict/update from P0 = R until it settles: the same P (independent of scipy's solver)
    Pk = R.copy()
    for _ in range(20000):
        Kk = Pk @ np.linalg.inv(Pk + R)
        Pk = m.phi @ ((np.eye(6) - Kk) @ Pk) @ m.phi.T + m.qd
    np.testing.assert_allclose(Pk, P, rtol=1e-6, atol=1e-14)
    assert np.max(np.abs(np.linalg.eigvals(m.phi @ (np.eye(6) - K)))) < 1.0


def test_bad_step_or_density_is_refused():
    A, B = cw_matrices(N_LEO)
    with pytest.raises(ValueError, match="dt"):
        discrete_model(A, B, B, 1e-9, 0.0)
    with pytest.raises(ValueError, match="q"):
        discrete_model(A, B, B, -1.0, 1.0)
