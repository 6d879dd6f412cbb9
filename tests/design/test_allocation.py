"""LLFR control allocation (design.allocation), Azizi2009 eqs. (2)-(3), (6), Lemma 1; SPEC P4.6-1.

Truths: the KKT system of the equality-constrained quadratic program solved as one linear system
(independent of the J_aug and least-norm forms), the SPEC P4.3 closed forms (a polynomial identity
checked at random points, tolerance 1e-10 relative: round-off of 4x4 determinants) and the SPEC's
reference numbers (DET = 3.7764, q1 = 2.64, q2 = 1.1364, C = [-1, 2, 1, -1]; printed to 4-5 digits).
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from formation_ftc.design.allocation import (
    allocate,
    allocate_augmented,
    augmented_matrix,
    chain_matrix,
    closed_form_n4,
    perturbation_coefficients,
    perturbation_matrix,
    validate_allocation_inputs,
)


def _kkt(alpha, b_hat, p):
    """min sum alpha u^2/2 s.t. J u = p via the KKT matrix [[W, J^T], [J, 0]]."""
    J = np.asarray(chain_matrix(b_hat))
    n = len(alpha)
    K = np.zeros((2 * n - 1, 2 * n - 1))
    K[:n, :n] = np.diag(alpha)
    K[:n, n:] = -J.T
    K[n:, :n] = J
    rhs = np.concatenate([np.zeros(n), p])
    return np.linalg.solve(K, rhs)[:n]


@pytest.mark.parametrize("n", [3, 4, 5, 8])
def test_least_norm_and_augmented_forms_equal_kkt_solution(n):
    rng = np.random.default_rng(n)
    for _ in range(5):
        alpha = rng.uniform(0.2, 10.0, n)
        b_hat = rng.uniform(0.3, 1.5, n)
        p = rng.normal(size=n - 1)
        ref = _kkt(alpha, b_hat, p)
        np.testing.assert_allclose(
            np.asarray(allocate(alpha, b_hat, p)), ref, rtol=1e-10, atol=1e-12
        )
        np.testing.assert_allclose(
            np.asarray(allocate_augmented(alpha, b_hat, p)), ref, rtol=1e-10, atol=1e-12
        )
        # constraints (2) hold and the optimality row sum alpha_i u_i / b_hat_i = 0 (E004-02)
        np.testing.assert_allclose(np.asarray(chain_matrix(b_hat)) @ ref, p, atol=1e-11)
        assert abs(np.sum(alpha * ref / b_hat)) < 1e-11


def test_allocation_is_the_minimum_cost_feasible_input():
    rng = np.random.default_rng(3)
    alpha, b_hat, p = (
        np.array([1.0, 6.0, 1.0, 1.0]),
        np.array([1.0, 0.88, 1.0, 1.0]),
        rng.normal(size=3),
    )
    u = np.asarray(allocate(alpha, b_hat, p))
    null = 1.0 / b_hat  # J (1/b_hat) = 0
    cost = lambda v: 0.5 * np.sum(alpha * v**2)  # noqa: E731
    for s in (-1e-2, 1e-3, 0.5):
        assert cost(u + s * null) > cost(u)


def test_spec_reference_numbers_n4():
    pc = perturbation_coefficients([1, 1, 1, 1], [1, 0.88, 1, 1], 1)
    assert pc.q1 == pytest.approx(2.64, rel=1e-12)
    assert pc.q2 == pytest.approx(1.1364, abs=5e-5)
    assert pc.q1 / pc.q2 == pytest.approx(2.3232, abs=5e-5)
    assert pc.det(1.0) == pytest.approx(3.7764, abs=5e-5)
    np.testing.assert_allclose(pc.f, [-1, 2, 1, -1], atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.floats(0.2, 10.0), min_size=4, max_size=4),
    st.lists(st.floats(0.3, 1.5), min_size=4, max_size=4),
)
def test_closed_forms_equal_numeric_determinant_and_cofactors(alpha, b):
    alpha, b = np.array(alpha), np.array(b)
    bh2 = b[1]
    cf = closed_form_n4(alpha, b, bh2)
    J = np.asarray(augmented_matrix(alpha, b))
    det = np.linalg.det(J)
    assert cf["DET"] == pytest.approx(-det, rel=1e-10)  # E004-03: DET = -det(J_aug)
    pc = perturbation_coefficients(alpha, b, 1)
    assert pc.q1 == pytest.approx(cf["q1"], rel=1e-10)
    assert pc.q2 == pytest.approx(cf["q2"], rel=1e-10)
    np.testing.assert_allclose(pc.f, cf["C"], rtol=1e-9, atol=1e-12)
    # inverse column = cofactor / det (adjugate), independent route
    inv = np.linalg.inv(J)
    np.testing.assert_allclose(inv[1, :], cf["C"] / det, rtol=1e-8, atol=1e-12)


def test_cofactors_free_of_alpha2_and_b_hat2():  # Lemma 1
    base = perturbation_coefficients([1.0, 1.0, 2.0, 0.5], [1.1, 0.88, 0.9, 1.2], 1).f
    for a2, bh2 in [(5.0, 0.88), (1.0, 0.5), (9.0, 1.4)]:
        f = perturbation_coefficients([1.0, a2, 2.0, 0.5], [1.1, bh2, 0.9, 1.2], 1).f
        np.testing.assert_allclose(f, base, rtol=1e-10)


def test_perturbation_matrix_structure_and_decrease_in_alpha2():
    alpha, b_hat, eps = np.array([1.0, 1.0, 1.0, 1.0]), np.array([1.0, 0.88, 1.0, 1.0]), 0.08
    D = perturbation_matrix(alpha, b_hat, 1, eps)
    pc = perturbation_coefficients(alpha, b_hat, 1)
    np.testing.assert_allclose(D[0], pc.d(eps, 1.0), atol=1e-14)
    np.testing.assert_allclose(D[1], -D[0], atol=1e-14)
    np.testing.assert_allclose(D[2], 0.0, atol=1e-14)
    norms = [
        np.linalg.norm(perturbation_matrix([1, a, 1, 1], b_hat, 1, eps), 2) for a in (1, 2, 5, 10)
    ]
    assert np.all(np.diff(norms) < 0)


@pytest.mark.parametrize(
    "alpha,b_hat,match",
    [
        ([1, 0, 1, 1], [1, 1, 1, 1], "alpha"),
        ([1, -2, 1, 1], [1, 1, 1, 1], "alpha"),
        ([1, 1, 1, 1], [1, 0.0, 1, 1], "b_hat"),
        ([1, 1, 1, 1], [1, float("nan"), 1, 1], "b_hat"),
        ([1, 1, 1], [1, 1, 1, 1], "shape"),
    ],
)
def test_bad_allocation_inputs_are_rejected(alpha, b_hat, match):
    with pytest.raises(ValueError, match=match):
        validate_allocation_inputs(alpha, b_hat)


def test_end_satellite_has_no_reduced_model():
    with pytest.raises(ValueError, match="interior"):
        perturbation_coefficients([1, 1, 1, 1], [1, 1, 1, 1], 0)
