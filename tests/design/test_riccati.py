"""CARE solver: closed-form truth (double integrator) and the Gui2022 P1/K (E002-05, SPEC P2.6 #1)."""

import numpy as np
import pytest

from formation_ftc.core.dynamics.cw import cw_matrices
from formation_ftc.design.riccati import care_residual, solve_care
from formation_ftc.papers.gui2022 import published as pub


def test_double_integrator_closed_form():
    # A = [[0,1],[0,0]], B = [0;1], Q = I, R = 1  ->  P = [[sqrt3, 1], [1, sqrt3]] (hand-solved CARE)
    A = np.array([[0.0, 1.0], [0.0, 0.0]])
    B = np.array([[0.0], [1.0]])
    sol = solve_care(A, B, np.eye(2), np.eye(1))
    np.testing.assert_allclose(sol.P, [[np.sqrt(3), 1.0], [1.0, np.sqrt(3)]], atol=1e-12)
    assert sol.residual <= 1e-12
    assert np.all(sol.closed_loop_eigenvalues.real < 0)


def test_gui2022_P1_and_K_from_Q_4e5():
    A, B = cw_matrices(pub.N_MEAN_MOTION)
    sol = solve_care(A, B, pub.CARE_Q_SCALE * np.eye(6), np.eye(3))
    # printed to 4 decimals -> |error| <= 5e-5 (reference 3.15e-5, E002-05)
    assert np.max(np.abs(sol.P - pub.P1_PRINTED)) <= 5e-5
    assert sol.residual <= 1e-12
    assert care_residual(sol.P, A, B, pub.CARE_Q_SCALE * np.eye(6), np.eye(3)) == pytest.approx(
        sol.residual
    )
    np.testing.assert_array_equal(np.round(B.T @ sol.P, 4) + 0.0, pub.K_PRINTED)


def test_other_Q_do_not_reproduce_printed_P1():
    A, B = cw_matrices(pub.N_MEAN_MOTION)
    P_I = solve_care(A, B, np.eye(6), np.eye(3)).P
    P_1e4 = solve_care(A, B, 1e-4 * np.eye(6), np.eye(3)).P
    assert P_I[0, 0] == pytest.approx(1.732, abs=1e-3)
    assert P_1e4[3, 3] == pytest.approx(0.1418, abs=1e-4)


def test_bad_input():
    A, B = cw_matrices(0.0015)
    with pytest.raises(ValueError, match="R must be"):
        solve_care(A, B, np.eye(6), -np.eye(3))
    with pytest.raises(ValueError, match="shapes"):
        solve_care(A, B, np.eye(5), np.eye(3))
    # (A, B) not stabilisable: unstable mode not reachable
    with pytest.raises(ValueError):
        solve_care(np.eye(2), np.array([[1.0], [0.0]]), np.eye(2), np.eye(1))
