"""Scenario validation of the switched-formation types and the Yang2013 theorem-condition flags that
``check`` states for the switching supervisor (bad input is rejected or flagged with the violated
inequality)."""

import pytest

import formation_ftc as ftc
from formation_ftc.config.loader import ScenarioError
from formation_ftc.papers.yang2013.conditions import design_quantities


def conditions(overrides=None):
    return {
        c.reference + " " + c.name: c
        for c in ftc.check(ftc.load_scenario("yang2013-controller-fault", overrides))
    }


def failing(conds):
    return [k for k, c in conds.items() if c.required and c.holds is False]


def test_builtin_scenarios_load_and_all_conditions_hold():
    for name in ("yang2013-healthy", "yang2013-controller-fault"):
        sc = ftc.load_scenario(name)
        assert [len(m.members) for m in sc.section("supervisor").modes] == [
            3,
            5,
            5,
            5,
            4,
        ]  # SPEC P1.6-5 (mode 5 with the zero-row placeholder)
        q = design_quantities(sc)
        assert q["dwell_time_required"] == pytest.approx(542.8, abs=0.1)
    assert failing(conditions()) == []


def test_wrong_variation_shape_is_rejected():
    with pytest.raises(
        ScenarioError, match=r"modes\[1\]\.variation has shape \(2, 3\); expected \(5, 3\)"
    ):
        ftc.load_scenario(
            "yang2013-healthy", {"supervisor.modes.1.variation": [[1, 0, 0], [0, 1, 0]]}
        )
    with pytest.raises(
        ScenarioError, match=r"modes\[4\]\.variation has shape \(3, 4\); expected \(3, 5\)"
    ):
        ftc.load_scenario(
            "yang2013-healthy",
            {"supervisor.modes.4.variation": [[1, 0, 0, 0], [0, 0, 0, 0], [0, 0, 1, 0]]},
        )


def test_mode_without_spacecraft_is_rejected():
    with pytest.raises(ScenarioError, match="at least one spacecraft"):
        ftc.load_scenario("yang2013-healthy", {"supervisor.modes.2.members": []})
    with pytest.raises(ScenarioError, match="at least one spacecraft"):
        ftc.load_scenario("yang2013-healthy", {"supervisor.modes.0.members": [0]})


def test_other_structural_errors_are_rejected():
    with pytest.raises(ScenarioError, match=r"not a multiple of simulation.dt"):
        ftc.load_scenario("yang2013-healthy", {"supervisor.modes.1.start": 1000.01})
    with pytest.raises(ScenarioError, match=r"spacecraft 6 exceeds plant.count = 5"):
        ftc.load_scenario("yang2013-healthy", {"plant.count": 5})
    with pytest.raises(ScenarioError, match=r"initial_state must give exactly the members"):
        ftc.load_scenario("yang2013-healthy", {"plant.initial_state.2.spacecraft": 4})
    with pytest.raises(ScenarioError, match=r"onset = 3800.01 s is not a multiple"):
        ftc.load_scenario("yang2013-controller-fault", {"actuator.faults.0.onset": 3800.01})
    with pytest.raises(ScenarioError, match=r"greater than 0"):
        ftc.load_scenario("yang2013-healthy", {"controller.K2": -0.01})  # E001-01


def test_dwell_time_violation_is_flagged_with_21():
    conds = conditions({"supervisor.modes.1.start": 500.0})  # mode 1 active for 500 s < 542.8 s
    bad = failing(conds)
    assert len(bad) == 1 and "(21)" in bad[0]
    c = conds[bad[0]]
    assert c.value == "500" and c.requirement.startswith(">= 542.8")


def test_joining_state_above_22_is_flagged():
    conds = conditions(
        {"supervisor.modes.4.new_states.0.e_R": [0.8, 0.5, 0.0]}
    )  # |x6| = 0.943 > 0.9
    bad = failing(conds)
    assert len(bad) == 1 and "(22)" in bad[0] and "spacecraft 6" in bad[0]


def test_early_fault_violates_29_and_initial_state_24():
    bad = failing(conditions({"actuator.faults.0.onset": 3300.0}))  # dt1 = 300 < dt2 = 700
    assert len(bad) == 1 and "(29)" in bad[0]
    bad = failing(conditions({"plant.initial_state.0.e_R": [2.5, 0.0, 0.0]}))
    assert len(bad) == 1 and "(24)" in bad[0]


def test_gains_must_realise_eta_and_eta1():
    bad = failing(conditions({"controller.K2": 0.005}))  # rate 0.0025 < eta/2
    assert len(bad) == 1 and "gains realise eta" in bad[0]
    bad = failing(conditions({"actuator.faults.0.K2_faulty": -0.03}))  # growth 0.03 > eta1 = 0.01
    assert len(bad) == 1 and "eta1 bounds" in bad[0]


def test_theorems_are_not_applicable_to_another_law():
    """The switching supervisor with another law: the theorems state nothing."""
    from formation_ftc.papers.yang2013.conditions import conditions as yang_conditions

    sc = ftc.load_scenario("yang2013-healthy")
    # S (informative), eta, K3, four epsilon inequalities, (21), (24), (22), |d_i|, |iota_i|
    assert len(yang_conditions(sc)) == 12
    other = sc.model_copy()  # the same scenario with another law's section (a pd law)
    other._sections = {
        **sc._sections,
        "controller": ftc.load_scenario("cw-pd-fault").section("controller"),
    }
    assert yang_conditions(other) == []


def test_compositions_that_cannot_work_are_rejected():
    from formation_ftc.config import loader

    raw = loader.read_raw("yang2013-healthy")[0]
    without = {k: v for k, v in raw.items() if k not in ("supervisor", "evaluations")}
    with pytest.raises(
        ScenarioError,
        match=r'plant switched-formation needs the prescribed mode sequence .*"switching"',
    ):
        ftc.load_scenario(without)
    with pytest.raises(
        ScenarioError,
        match=r'controller yang2013-force-torque needs the measured error state .*"tracking-error"',
    ):
        ftc.load_scenario(dict(raw, sensors={"type": "relative-state"}))
