"""Condition calculators of Yang2013 Theorems 1-2 against SPEC P1.6 (reviewer numbers) and closed forms.

Numbers: D = 0.1, S_F = sqrt 5, S_2 = sqrt 3, |S_45|_2 = 1, S eps1 + eps2 = 0.8472, dwell-time bound
200 ln(15.090) = 542.8 s (525.3 s with sqrt 3, 506.6 s with (S+1), E001-07), (24) 2.518, (22) 0.9,
(29) = 3.0, envelope 3.018.
"""

import numpy as np
import pytest

from formation_ftc.design import dwell_time as dw

S12 = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 0], [1, 0, 0]], float)
S45 = np.array([[1, 0, 0, 0, 0], [0, 0, 0, 0, 0], [0, 0, 1, 0, 0]], float)
MATS = [S12, np.eye(5), np.eye(5), S45]
ZETA, ETA, EPS, EPS1, EPS2, TAU = 5.0, 0.01, 0.9, 0.2, 0.4, 80.0


def test_variation_norms_e001_04():
    assert dw.variation_norm(S12, "frobenius") == pytest.approx(np.sqrt(5), abs=1e-12)
    assert dw.variation_norm(S12, "induced2") == pytest.approx(np.sqrt(3), abs=1e-12)
    assert dw.variation_norm(S45, "induced2") == pytest.approx(1.0, abs=1e-12)
    assert dw.max_variation_norm(MATS, "frobenius") == pytest.approx(np.sqrt(5), abs=1e-12)
    assert dw.max_variation_norm(MATS, "induced2") == pytest.approx(np.sqrt(3), abs=1e-12)
    # the induced norm is the tight one: |S X| <= |S|_2 |X| with equality for the top singular vector
    X = np.array([1.0, 0.0, 0.0])
    assert np.linalg.norm(S12 @ X) == pytest.approx(np.sqrt(3))
    with pytest.raises(ValueError, match="frobenius"):
        dw.variation_norm(S12, "max")


def test_spec_p1_6_numbers():
    D = dw.disturbance_bound(0.06, 0.08)
    assert D == pytest.approx(0.1, abs=1e-15)
    S = np.sqrt(5)
    assert S * EPS1 + EPS2 == pytest.approx(0.8472, abs=1e-4)
    assert all(i.holds for i in dw.check_epsilons(EPS, EPS1, EPS2, S))
    t21 = dw.dwell_time_bound(ETA, S, ZETA, D, EPS, EPS1, TAU)
    assert t21 == pytest.approx(200 * np.log(15.090), abs=0.1)
    assert t21 == pytest.approx(542.8, abs=0.1)
    assert dw.dwell_time_bound(ETA, np.sqrt(3), ZETA, D, EPS, EPS1, TAU) == pytest.approx(
        525.3, abs=0.1
    )
    assert dw.dwell_time_bound(ETA, S, ZETA, D, EPS, EPS1, TAU, s_offset=1.0) == pytest.approx(
        506.6, abs=0.1
    )
    assert dw.dwell_time_bound(ETA, S, ZETA, D, EPS, EPS1, tau=600.0) == 600.0  # tau dominates
    assert dw.initial_state_bound(EPS, S, ZETA, D) == pytest.approx(2.518, abs=1e-3)
    assert dw.new_state_bound(EPS2, ZETA, D) == pytest.approx(0.9, abs=1e-12)
    assert dw.state_envelope(EPS, S, ZETA, D) == pytest.approx(3.018, abs=1e-3)
    assert dw.pre_switch_bound(EPS1, ZETA, D) == pytest.approx(0.7, abs=1e-12)
    assert dw.condition_29_margin(ETA, 0.01, 800.0, 200.0) == pytest.approx(3.0, abs=1e-12)


def test_checks_flag_violations_with_the_inequality():
    D, S = 0.1, np.sqrt(5)
    ok = dw.check_dwell_time(1000.0, ETA, S, ZETA, D, EPS, EPS1, TAU)
    bad = dw.check_dwell_time(500.0, ETA, S, ZETA, D, EPS, EPS1, TAU)
    assert ok.holds and not bad.holds
    assert (
        bad.reference == "(21)"
        and "VIOLATED" in str(bad)
        and bad.rhs == pytest.approx(542.8, abs=0.1)
    )
    assert not dw.check_new_state(0.95, EPS2, ZETA, D).holds
    assert dw.check_new_state(0.2, EPS2, ZETA, D).holds
    assert not dw.check_initial_state(2.6, EPS, S, ZETA, D).holds
    assert dw.check_condition_29(ETA, 0.01, 800.0, 200.0).holds
    # (29) <=> dt1 >= dt2 when eta = eta1: a fault at 3400 s in [3000, 4000) is not tolerable
    late = dw.check_condition_29(ETA, 0.01, 400.0, 600.0)
    assert not late.holds and late.lhs == pytest.approx(-1.0)
    assert not dw.check_epsilons(EPS, 0.3, EPS2, S)[-1].holds  # S eps1 + eps2 = 1.07 > 0.9


def test_gain_choice_realises_eta_and_eta1():
    # closed loop e'' + K2 e' + (K1+1) e = 0: rate K2/2 = eta/2; faulty K2f = -0.01: growth eta1/2
    assert dw.translational_decay_rate(0.005, 0.01) == pytest.approx(0.005, rel=1e-12)
    assert dw.translational_decay_rate(0.005, -0.01) == pytest.approx(-0.005, rel=1e-12)
    assert dw.gains_for_decay_rate(0.01) == (0.005, 0.01)
    # overdamped loop: rate is the slow root, not K2/2
    assert dw.translational_decay_rate(0.0, 3.0) == pytest.approx((3 - np.sqrt(5)) / 2, rel=1e-12)
    # printed (18) with nu's: eta = 2 min[...]; also zeta = max sqrt(n_j eps)
    assert dw.eta_from_gains(0.005, 0.02, 2.0, 2.0, 1.0, 0.01, 0.5, 1.0) == pytest.approx(0.01)
    assert (
        dw.eta_from_gains(0.005, 0.01, 0.2, 1.0, 1.0, 0.001, 0.05, 0.1) < 0
    )  # SPEC gains: (18) fails (E001-03)
    assert dw.zeta_from_epsilon([3, 5, 5, 5, 4], 5.0) == pytest.approx(5.0)
    assert dw.lyapunov_epsilon(1e-4, 0.2, [150.0]) == pytest.approx(5.0)
