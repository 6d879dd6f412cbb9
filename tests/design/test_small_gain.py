"""Certified H-infinity norms (design.small_gain.hinf_norm) and the Azizi2009 Theorem 1 margin.

Truths: closed-form norms (first order: DC gain; second order 1/(2 zeta sqrt(1 - zeta^2)) for
zeta < 1/sqrt(2)); a dense frequency grid with local refinement (implemented here, independently of the
package) as a cross-check on random MIMO systems; the bounded-real certificate must refuse any gamma
below the true norm.
"""

import numpy as np
import pytest
import scipy.optimize

from formation_ftc.design.flfr import error_dynamics_matrix
from formation_ftc.design.small_gain import hinf_norm, kyp_certificate, small_gain_margin


def _sigma(A, B, C, D, w):
    G = C @ np.linalg.solve(1j * w * np.eye(A.shape[0]) - A, B) + D
    return np.linalg.svd(G, compute_uv=False)[0]


def grid_norm(A, B, C, D, w_min=1e-4, w_max=1e3, n=4000):
    """Cross-check only: max over a log grid (plus omega = 0), refined around the grid peak."""
    w = np.concatenate([[0.0], np.logspace(np.log10(w_min), np.log10(w_max), n)])
    s = np.array([_sigma(A, B, C, D, x) for x in w])
    i = int(np.argmax(s))
    best = s[i]
    if 0 < i < w.size - 1:
        res = scipy.optimize.minimize_scalar(
            lambda lw: -_sigma(A, B, C, D, 10.0**lw),
            bounds=(np.log10(max(w[i - 1], 1e-12)), np.log10(w[i + 1])),
            method="bounded",
            options={"xatol": 1e-12},
        )
        best = max(best, -res.fun)
    return best


def second_order(wn, zeta):
    A = np.array([[0.0, 1.0], [-(wn**2), -2 * zeta * wn]])
    return A, np.array([[0.0], [wn**2]]), np.array([[1.0, 0.0]]), np.zeros((1, 1))


def test_first_order_dc_gain_and_feedthrough():
    r = hinf_norm([[-4.0]], [[1.0]], [[1.0]])
    assert (
        r.certified
        and 0.25 <= r.value <= 0.25 * (1 + 2e-6)
        and r.lower == pytest.approx(0.25, rel=1e-14)
    )
    r = hinf_norm([[-4.0]], [[1.0]], [[1.0]], [[-3.0]])  # G(0) = 0.25 - 3, |G| -> 3 at infinity
    assert 2.75 <= r.value <= 3 * (1 + 2e-6) and r.lower >= 2.75


@pytest.mark.parametrize("wn", [1e-6, 1e5, 5e3, 3.0])
def test_lightly_damped_resonance_anywhere(wn):
    zeta = 1e-3
    true = 1 / (2 * zeta * np.sqrt(1 - zeta**2))  # = 500.00025
    r = hinf_norm(*second_order(wn, zeta))
    assert r.certified, r.reason
    assert true * (1 - 1e-12) <= r.value <= true * (1 + 2e-6)
    assert true * (1 - 2e-6) <= r.lower <= true * (1 + 1e-12)
    assert r.omega_peak == pytest.approx(wn * np.sqrt(1 - 2 * zeta**2), rel=1e-3)
    assert "KYP" in r.describe() and "relative gap" in r.describe()


@pytest.mark.parametrize("wn", [1e-6, 1e5])
def test_grid_misses_what_the_certificate_catches(wn):
    """The old 1e-4 ... 1e3 rad/s grid reads ~1 for these systems: an unsafe small-gain margin."""
    sysm = second_order(wn, 1e-3)
    assert grid_norm(*sysm) < 1.1
    assert hinf_norm(*sysm).value > 499.0


def test_certificate_refuses_gamma_below_the_norm():
    A, B, C, D = second_order(2.0, 0.05)
    true = 1 / (2 * 0.05 * np.sqrt(1 - 0.05**2))
    assert kyp_certificate(A, B, C, D, true * 1.001)[0]
    ok, why = kyp_certificate(A, B, C, D, true * 0.999)
    assert not ok and why


def test_pure_integrator_has_infinite_norm_and_fails_small_gain():
    r = hinf_norm([[0.0]], [[1.0]], [[1.0]])
    assert np.isinf(r.value) and "not Hurwitz" in r.reason and "unbounded" in r.reason
    assert "inf" in r.describe()
    A = np.array([[0.0, 1.0], [0.0, -1.0]])  # integrator + lag
    sg = small_gain_margin(A)
    assert np.isinf(sg.gamma1) and sg.b_delta == 0.0
    assert not sg.holds(0.0) and not sg.holds(1e-12)
    assert "not Hurwitz" in sg.certificate


def test_azizi_gamma1_sqrt2():
    A = error_dynamics_matrix(2.0, 3.0)
    r = hinf_norm(A, np.eye(4), A, np.zeros((4, 4)))
    assert np.sqrt(2) <= r.value <= np.sqrt(2) * (1 + 2e-6)
    assert r.lower == pytest.approx(np.sqrt(2), rel=2e-6)
    assert r.lower <= grid_norm(A, np.eye(4), A, np.zeros((4, 4))) * (1 + 1e-9)


def test_random_mimo_systems_agree_with_the_grid_cross_check():
    rng = np.random.default_rng(7)
    for _ in range(6):
        n, m, p = 4, 2, 3
        M = rng.normal(size=(n, n))
        A = M - (np.max(np.linalg.eigvals(M).real) + rng.uniform(0.2, 1.0)) * np.eye(n)  # Hurwitz
        B, C, D = rng.normal(size=(n, m)), rng.normal(size=(p, n)), 0.1 * rng.normal(size=(p, m))
        r = hinf_norm(A, B, C, D)
        g = grid_norm(A, B, C, D, 1e-3, 1e3, 3000)
        assert r.certified
        assert g <= r.value * (1 + 1e-12)  # the certified value is an upper bound
        assert r.value <= g * (
            1 + 1e-5
        )  # and tight (the grid is fine for these well-damped systems)
