"""FLFR design (design.flfr) and small-gain bound (design.small_gain); Azizi2009 eqs. (7)-(11),
Theorems 1-2; SPEC P4.6-5/6, E004-05/07.

Truths: closed-form H-infinity norms (first/second order), the closed-form forced response of an LTI
system to a sinusoid (steady state G(j omega) plus expm transient), the inverse relation of eq. (11)
(the designed alpha puts bound (8) exactly at e_s / (1 - pi)), and the SPEC reference numbers
(printed to 3 digits: tolerance 0.006 on alpha, 0.0015 on H).
"""

import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg

from formation_ftc.design.flfr import (
    InfeasibleSpecification,
    alpha_deterministic,
    alpha_probabilistic,
    convolution_supremum,
    design_flfr,
    disturbance_floor,
    error_dynamics_matrix,
    simulate_reduced_model,
    validate_violation_probability,
)
from formation_ftc.design.small_gain import small_gain_margin

R, OMEGA = 200 / np.sqrt(2), 0.1


def xdd_rel(t):
    """Desired relative accelerations of the rotating square (SPEC P4.2), pairs (1,2), (2,3), (3,4)."""
    i = jnp.arange(4)
    a = -(OMEGA**2) * R * jnp.cos(OMEGA * t + jnp.pi / 4 + i * jnp.pi / 2)
    return a[1:] - a[:-1]


def test_small_gain_gamma1_is_sqrt2():  # E004-05
    sg = small_gain_margin(error_dynamics_matrix(2.0, 3.0))
    assert np.sqrt(2) <= sg.gamma1 <= np.sqrt(2) * (1 + 2e-6)  # certified upper bound, gap <= rtol
    assert sg.norm.lower <= np.sqrt(2) * (1 + 1e-12)
    assert sg.b_delta == pytest.approx(1 / np.sqrt(2), rel=2e-6)
    assert sg.holds(0.067) and not sg.holds(0.8)
    assert "certified" in sg.certificate and "KYP" in sg.certificate


def test_reduced_model_simulation_matches_closed_form_sinusoid_response():
    A = error_dynamics_matrix(2.0, 3.0).copy()
    A[1, 3], A[3, 1] = 0.05, -0.05  # some coupling
    b = np.array([0.0, 1.0, 0.0, -1.0])
    W = 0.7 - 0.4j  # w(t) = Re(W e^{j omega t})
    w_fn = lambda t: jnp.real(W * jnp.exp(1j * OMEGA * t))  # noqa: E731
    xs, peak = simulate_reduced_model(A, w_fn, 40.0, 1e-3, record_every=100)
    t = np.arange(xs.shape[0]) * 0.1
    Xs = np.linalg.solve(1j * OMEGA * np.eye(4) - A, b * W)
    ref = np.array(
        [
            np.real(Xs * np.exp(1j * OMEGA * tt)) - scipy.linalg.expm(A * tt) @ np.real(Xs)
            for tt in t
        ]
    )
    np.testing.assert_allclose(xs, ref, atol=1e-11)
    assert np.all(peak >= np.max(np.abs(ref), axis=0) - 1e-11)


def test_alpha_equations_invert_the_bound():
    H, q1, q2, b_eps, e_s = 3.0, 2.64, 1.1364, 0.08, 0.03
    for p in (0.0, 0.15, 0.4):
        a = alpha_probabilistic(b_eps, H, q1, q2, e_s, p)
        assert b_eps * (1 - p) * H / (q2 * a + q1) == pytest.approx(e_s, rel=1e-12)
    assert alpha_deterministic(b_eps, H, q1, q2, e_s) == alpha_probabilistic(
        b_eps, H, q1, q2, e_s, 0.0
    )


@pytest.mark.parametrize("pi", [1.0, 1.2, -0.1, float("nan")])
def test_violation_probability_outside_range_is_rejected(pi):
    with pytest.raises(ValueError, match="0 <= pi < 1"):
        validate_violation_probability(pi)


def test_pi_zero_is_accepted_as_deterministic_case():
    assert validate_violation_probability(0.0) == 0.0


def test_e_s_below_floor_is_infeasible():
    with pytest.raises(InfeasibleSpecification, match="floor"):
        alpha_probabilistic(0.08, 3.0, 2.64, 1.13, e_s=1e-5, pi=0.0, floor=2e-5)


def test_disturbance_floor_nominal_closed_form():
    # nominal A: G_12(s) = 1/(s^2 + 3 s + 2), G_14 = 0 -> sup |.| = 1/2 at omega = 0
    T = disturbance_floor(error_dynamics_matrix(2.0, 3.0), 2e-5)
    assert 0.5 * 2e-5 <= T[0] <= 0.5 * 2e-5 * (1 + 2e-6)  # certified upper bound on the floor
    assert 0.5 * 2e-5 <= T[2] <= 0.5 * 2e-5 * (1 + 2e-6)


def test_disturbance_floor_of_unstable_loop_is_infinite():
    A = error_dynamics_matrix(2.0, 3.0)
    A[1, 1] = +0.5  # unstable block
    assert np.all(np.isinf(disturbance_floor(A, 1e-5)))


def test_design_matches_spec_reference_numbers():
    des = design_flfr(
        [1, 1, 1, 1],
        [1, 0.88, 1, 1],
        1,
        0.08,
        2.0,
        3.0,
        0.03,
        [0.0, 0.15, 0.2, 0.4],
        xdd_rel,
        300.0,
        1e-3,
        b_ext=2e-5,
    )
    assert des.verdict == "feasible"
    assert des.H == pytest.approx(3.003, abs=1.5e-3)
    assert des.H_nominal == pytest.approx(2.811, abs=1.5e-3)
    for p, ref in zip((0.0, 0.15, 0.2, 0.4), (4.72, 3.67, 3.31, 1.90), strict=True):
        assert des.alpha[p] == pytest.approx(ref, abs=6e-3)
    for p, ref in zip((0.0, 0.15, 0.2, 0.4), (4.27, 3.28, 2.95, 1.63), strict=True):
        assert des.alpha_nominal_H[p] == pytest.approx(ref, abs=6e-3)
    a = [des.alpha[p] for p in (0.0, 0.15, 0.2, 0.4)]
    assert np.all(np.diff(a) < 0)  # decreasing in pi
    assert des.bound_at_reference == pytest.approx(0.0636, abs=1e-4)
    assert des.delta_norm_reference == pytest.approx(0.067, abs=1e-3)
    assert np.all(des.eig_clp.real < 0) and np.all(np.abs(des.eig_clp.imag) < 1e-12)  # SPEC P4.6-6
    # H from the simulated convolution equals sup of the same response in the nominal case
    nom = convolution_supremum(
        error_dynamics_matrix(2.0, 3.0), xdd_rel, 300.0, 1e-3, des.coefficients.f[:3]
    )
    assert des.H_nominal == pytest.approx(max(nom[0], nom[2]), rel=1e-12)


def test_design_reports_infeasible_with_floor():
    des = design_flfr(
        [1, 1, 1, 1],
        [1, 0.88, 1, 1],
        1,
        0.08,
        2.0,
        3.0,
        0.03,
        [0.0],
        xdd_rel,
        20.0,
        1e-2,
        b_ext=1.0,
    )
    assert des.verdict == "infeasible"
    assert "floor" in des.message and des.alpha[0.0] is None
    assert des.floor > 0.03


def test_sigma_max_agrees_with_python_control_frequency_response():
    import control

    from formation_ftc.design.small_gain import sigma_max_response

    A = error_dynamics_matrix(2.0, 3.0)
    sys = control.ss(A, np.eye(4), A, np.zeros((4, 4)))
    for w in (0.01, 0.5, 1.0, 7.0):
        G = np.asarray(sys(1j * w))
        ref = np.linalg.svd(G, compute_uv=False)[0]
        assert sigma_max_response(A, np.eye(4), A, np.zeros((4, 4)), w)[0] == pytest.approx(
            ref, rel=1e-12
        )


def test_convolution_supremum_is_remembered_per_exact_input(monkeypatch):
    # a second design of the same formation (another violation probability or mission bound) reuses the
    # simulated suprema: same values, no simulation, and a caller's copy cannot alter what is kept
    import formation_ftc.design.flfr as flfr

    A = error_dynamics_matrix(2.0, 3.0)
    first = convolution_supremum(A, xdd_rel, 5.0, 1e-2, (1.0, 0.5, 0.25))
    calls = []
    real = flfr.simulate_reduced_model
    monkeypatch.setattr(
        flfr, "simulate_reduced_model", lambda *a, **k: calls.append(a) or real(*a, **k)
    )
    again = convolution_supremum(A.copy(), xdd_rel, 5.0, 1e-2, [1.0, 0.5, 0.25])
    np.testing.assert_array_equal(again, first)
    assert calls == []
    again[:] = -1.0
    np.testing.assert_array_equal(
        convolution_supremum(A, xdd_rel, 5.0, 1e-2, (1.0, 0.5, 0.25)), first
    )
    other = convolution_supremum(
        A + 1e-9, xdd_rel, 5.0, 1e-2, (1.0, 0.5, 0.25)
    )  # another matrix: simulated
    assert len(calls) == 1 and not np.array_equal(other, first)
    _, peak = real(A, xdd_rel, 5.0, 1e-2, (1.0, 0.5, 0.25))
    np.testing.assert_array_equal(first, peak)  # what is remembered is the simulation's result
