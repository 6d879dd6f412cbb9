"""Scenario validation (bad input) and the design conditions / derived values (SPEC P3.6-1..4) of the
composed Mehrabian scenarios (conditions registered for controller ``networked-el-hinf``)."""

from __future__ import annotations

import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.config.loader import ScenarioError
from formation_ftc.papers.mehrabian import conditions

NAMES = ["mehrabian-no-reconfig", "mehrabian-identification", "mehrabian-isolation"]


@pytest.mark.parametrize("name", NAMES)
def test_builtin_scenarios_load_with_paper_data(name):
    s = ftc.load_scenario(name)
    assert s.scenario.method == "composed" and s.scenario.paper == "mehrabian"
    c = s.section("controller")
    assert (c.gamma, c.alpha, c.K, c.K_P, c.K_I, c.sigma, c.e_gain) == (
        0.6,
        0.86,
        20.0,
        0.16,
        0.001,
        0.5,
        1.0,
    )
    p = s.section("plant")
    assert s.simulation.horizon == 300.0 and p.disturbance_variance == 0.001
    assert (p.count, p.inertia_uncertainty, p.initial_attitude_range_deg) == (8, 0.1, (0.0, 60.0))
    assert p.inertia == c.nominal_inertia == (20.0, 18.0, 15.0)
    f = s.section("actuator").faults[0]
    assert (f.spacecraft, f.channel, f.start, f.end) == (1, 3, 40.0, 240.0)
    fdi = s.section("estimator")
    assert fdi.detected == (name != "mehrabian-no-reconfig")
    assert (fdi.delay, fdi.scale, fdi.bias) == (5.0, 1.0, -0.1)
    assert len(fdi.isolation) == (1 if name == "mehrabian-isolation" else 0)
    assert sorted(map(tuple, c.edges)) == sorted(
        [(1, 2), (2, 3), (3, 4), (4, 5), (5, 6), (6, 7), (7, 8), (8, 1), (1, 5), (3, 7)]
    )


def test_disconnected_graph_is_rejected():
    edges = [[1, 2], [2, 3], [3, 4], [4, 1], [5, 6], [6, 7], [7, 8], [8, 5]]
    with pytest.raises(ScenarioError, match="not connected"):
        ftc.load_scenario("mehrabian-identification", {"controller.edges": edges})


def test_singular_initial_attitudes_are_rejected():
    rows = [[10.0, 0.0, 0.0]] * 7 + [[90.0, 5.0, 5.0]]
    with pytest.raises(ScenarioError, match="singular at theta = \\+-90 deg"):
        ftc.load_scenario(
            "mehrabian-identification",
            {"plant.random_initial_attitude": False, "plant.initial_attitude_deg": rows},
        )
    with pytest.raises(ScenarioError, match="singular at theta = \\+-90 deg"):
        ftc.load_scenario(
            "mehrabian-identification", {"plant.initial_attitude_range_deg": [0.0, 90.0]}
        )
    ok = ftc.load_scenario(
        "mehrabian-identification",
        {
            "plant.random_initial_attitude": False,
            "plant.initial_attitude_deg": [[10.0, 0.0, 0.0]] * 8,
        },
    )
    assert ok.section("plant").initial_attitude_deg[0] == (10.0, 0.0, 0.0)


def test_other_bad_inputs_name_the_field():
    with pytest.raises(ScenarioError, match="controller.edges\\[0\\]"):
        ftc.load_scenario("mehrabian-identification", {"controller.edges": [[1, 9]]})
    with pytest.raises(ScenarioError, match="estimator.isolation\\[0\\]"):
        ftc.load_scenario("mehrabian-isolation", {"estimator.isolation.0.channel": 1})
    with pytest.raises(ScenarioError, match="controller.law|law"):
        ftc.load_scenario("mehrabian-identification", {"controller.law": "other"})
    with pytest.raises(ScenarioError, match="initial_attitude_deg is required"):
        ftc.load_scenario("mehrabian-identification", {"plant.random_initial_attitude": False})
    with pytest.raises(ScenarioError, match="evaluations\\[0\\]: fault_window"):
        ftc.load_scenario("mehrabian-identification", {"evaluations.0.fault_window": [50.0, 40.0]})


def _by_name(conds):
    return {c.name: c for c in conds}


def test_paper_gains_satisfy_conditions_and_derived_values():
    """SPEC P3.6-1..4: R = 0.058065 (17.22 = R^-1), sum Q_jn, Q_j, (11) = 1.584e-3, P_j min eig 3.07e-3."""
    conds = _by_name(ftc.check("mehrabian-identification"))
    assert all(c.holds for c in conds.values() if c.required)
    dq = conditions.design_quantities(20.0, 0.16, 0.001, 0.86, 0.6)
    assert dq.R == pytest.approx(0.058065, abs=1e-6) and dq.K_minus == pytest.approx(
        17.2222, abs=1e-4
    )
    np.testing.assert_allclose(dq.sum_Q_jn, [1.72e-5, 0.4403, 17.20], rtol=2e-3)
    np.testing.assert_allclose(dq.Q_j, [2.80e-6, 0.03168, 2.80], rtol=2e-3)
    assert dq.cond11 == pytest.approx(1.584e-3, rel=1e-9) and dq.cond11_swapped == pytest.approx(
        -0.32, abs=1e-3
    )
    assert dq.consensus_damping_literal == pytest.approx(0.011111, abs=1e-6)
    dq861 = conditions.design_quantities(20.0, 0.16, 0.001, 0.861, 0.6)
    # alpha = 0.861 reproduces the printed digits (truncated) except the middle Q_j entry (E003-05)
    assert conditions.matches_printed(
        dq861.sum_Q_jn, conditions.PRINTED["sum_Q_jn"], conditions.PRINTED_RESOLUTION["sum_Q_jn"]
    ) == [True, True, True]
    assert conditions.matches_printed(
        dq861.Q_j, conditions.PRINTED["Q_j"], conditions.PRINTED_RESOLUTION["Q_j"]
    ) == [True, False, True]
    assert (
        conditions.matches_printed(
            dq.sum_Q_jn, conditions.PRINTED["sum_Q_jn"], conditions.PRINTED_RESOLUTION["sum_Q_jn"]
        )[2]
        is False
    )  # 17.20 at 0.86
    assert conds["sum_n Q_jn"].holds is True
    for D in (10 * np.eye(3), 20 * np.eye(3)):
        P = conditions.lyapunov_matrix(D, 20.0, 0.16, 0.001)
        assert np.linalg.eigvalsh(P).min() == pytest.approx(3.07e-3, abs=1e-5)
    assert "17.2222" in conds["R_j"].value


def test_violated_gains_are_flagged_with_values():
    swapped = _by_name(
        ftc.check(
            ftc.load_scenario(
                "mehrabian-identification", {"controller.K_P": 0.001, "controller.K_I": 0.16}
            )
        )
    )
    c11 = swapped["(1 - alpha) K-bar^2 - 2 K-double-bar > 0"]
    assert c11.holds is False and "-0.32" in c11.value
    a = _by_name(
        ftc.check(ftc.load_scenario("mehrabian-identification", {"controller.alpha": 0.87}))
    )
    cm = a["consensus-mode damping of the literal law"]
    assert cm.holds is False and "-0.08" in cm.value
    assert a["0 < alpha < 1"].holds is True
    b = _by_name(
        ftc.check(
            ftc.load_scenario(
                "mehrabian-identification", {"controller.alpha": 1.2, "controller.K": 2.0}
            )
        )
    )
    assert b["0 < alpha < 1"].holds is False and b["K - I/gamma^2 > 0"].holds is False
    assert "-0.777778" in b["K - I/gamma^2 > 0"].value


def test_conditions_follow_the_law_on_any_plant():
    """The law's conditions come with controller networked-el-hinf on every plant it flies (the
    quaternion plants through the Euler sensors and the torque allocation), with that scenario's gains
    and graph."""
    names = {c.name for c in ftc.check("mehrabian-identification")}
    other = _by_name(ftc.check("compose-mehrabian-on-yang2013"))
    assert names <= set(other) | {"components fit together"}
    assert "components fit together" in other and other["0 < alpha < 1"].holds is True
    # the model inertia J^ of the P_j check is the law's stated one (25 kg m^2 there)
    P = conditions.lyapunov_matrix(np.diag([25.0] * 3), 20.0, 0.16, 0.001)
    assert f"{np.linalg.eigvalsh(P).min():.4g} (D = J^)" in other["P_j positive definite"].value
