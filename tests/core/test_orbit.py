"""Keplerian reference orbit vs Kepler's equation (independent of the theta ODE)."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from formation_ftc.core.orbit import KeplerOrbit, solve_kepler, true_anomaly_at


def test_li2020_constants():
    # SPEC.md P0.6-3: n_c = 1.078008e-3 rad/s, T_c = 5828.52 s (rel. 1e-5)
    orb = KeplerOrbit(a=7000e3, e=0.02)
    assert orb.mean_motion == pytest.approx(1.078008e-3, rel=1e-5)
    assert orb.period == pytest.approx(5828.52, rel=1e-5)


@pytest.mark.parametrize("e", [0.0, 0.02, 0.3, 0.7])
def test_theta_ode_matches_kepler_equation(e):
    """Integrating theta_dot(theta) at tight tolerance reproduces the Kepler-equation anomaly."""
    orb = KeplerOrbit(a=7000e3, e=e, theta0=0.3)
    t = np.linspace(0, orb.period, 50)
    sol = solve_ivp(
        lambda _, th: [float(orb.theta_dot(th[0]))],
        (0, orb.period),
        [orb.theta0],
        t_eval=t,
        rtol=1e-12,
        atol=1e-12,
        method="DOP853",
    )
    np.testing.assert_allclose(sol.y[0], true_anomaly_at(orb, t), atol=1e-8)
    # one full period advances theta by exactly 2 pi (SPEC P0.6-3: +-1e-6)
    assert sol.y[0][-1] - orb.theta0 == pytest.approx(2 * np.pi, abs=1e-6)


def test_theta_ddot_is_derivative_of_theta_dot():
    orb = KeplerOrbit(a=7000e3, e=0.1)
    th = np.linspace(0, 2 * np.pi, 13)
    h = 1e-6
    num = (orb.theta_dot(th + h) - orb.theta_dot(th - h)) / (2 * h) * orb.theta_dot(th)
    np.testing.assert_allclose(orb.theta_ddot(th), num, rtol=1e-6, atol=1e-15)


def test_solve_kepler_residual():
    M = np.linspace(-10, 10, 101)
    for e in (0.0, 0.5, 0.95):
        E = solve_kepler(M, e)
        np.testing.assert_allclose(E - e * np.sin(E), M, atol=1e-12)


@pytest.mark.parametrize("kw", [dict(a=-1, e=0.1), dict(a=7e6, e=1.0), dict(a=7e6, e=0.1, mu=0)])
def test_bad_orbit(kw):
    with pytest.raises(ValueError, match="orbit"):
        KeplerOrbit(**kw)
