"""The attitude league definition: it loads, every cell of every method validates (composition
included), the league's sampling reaches the plant's initial attitude, the method files' structural
options reach the actuator, and bad leagues are rejected naming the entry. No league run (too slow)."""

from __future__ import annotations

import copy
import shutil
import tomllib
from pathlib import Path

import numpy as np
import pytest
import tomli_w

import formation_ftc as ftc
from formation_ftc.config.loader import set_dotted
from formation_ftc.league.battery import load_battery
from formation_ftc.league.definition import LeagueError, builtin_leagues, load_league
from formation_ftc.league.runner import _campaign, plan_cells

ACTUATOR_CASES = ("none", "loe-50", "bias", "stuck", "outage", "intermittent", "degrading")


@pytest.fixture(scope="module")
def spec():
    return load_league("attitude")


@pytest.fixture(scope="module")
def cells(spec):
    return plan_cells(spec)  # raises LeagueError if any cell does not validate


def test_definition_loads(spec):
    assert "attitude" in builtin_leagues()
    assert spec.league.kind == "attitude"
    assert [m.name for m in spec.methods] == ["mehrabian", "mehrabian-active", "yang2013", "pd"]
    assert spec.truth["type"] == "attitude-truth" and spec.truth["state_frame"] == "lvlh"
    assert [lv.saturation for lv in spec.levels] == [None, 0.1]
    assert spec.league.requirement.metric == "rms_attitude_error"


def test_every_cell_validates_with_the_battery_and_level(spec, cells):
    battery = load_battery(spec.league.battery)
    assert set(cells) == {"mehrabian", "mehrabian-active", "yang2013", "pd"}
    for name, mcells in cells.items():
        # no method has a [network]: the communication cases do not apply, the actuator cases all do
        assert sorted({c.case for c in mcells}) == sorted(ACTUATOR_CASES), name
        assert len(mcells) == len(ACTUATOR_CASES) * len(spec.levels)
        for c in mcells:
            act = c.raw["actuator"]
            assert act["type"] == "fault-battery" and act["kind"] == battery[c.case].kind
            assert act.get("saturation") == (0.1 if c.level == "limited" else None)
            if (
                c.case == "bias"
            ):  # torque magnitudes of the battery: 0.5 N m, or half the 0.1 N m limit
                assert act["bias"] == pytest.approx(0.05 if c.level == "limited" else 0.5)
            assert act.get("euler_allocation", False) is name.startswith("mehrabian")
            assert c.raw["plant"] == spec.truth and c.raw["simulation"]["horizon"] == 300.0
            # the league scores a method's fault detector (mehrabian's) with fdi-scores too
            fdi = ["fdi-scores"] if name == "mehrabian" else []
            fdi = ["fdi-scores", "identification-scores"] if name == "mehrabian-active" else fdi
            assert [e["type"] for e in c.raw["evaluations"]] == ["attitude-scores", *fdi]
    mehrabian = cells["mehrabian"][0].raw
    assert mehrabian["sensors"]["type"] == "quaternion-euler"
    # the law reconfigures on detected, not scripted, faults
    assert mehrabian["estimator"]["type"] == "attitude-residual-fdi"
    assert all("estimator" not in c.raw for m in ("pd", "yang2013") for c in cells[m])
    assert "sensors" not in cells["pd"][0].raw and "sensors" not in cells["yang2013"][0].raw
    assert {c.raw["simulation"]["dt"] for m in cells.values() for c in m} == {0.05}


def test_campaign_samples_the_initial_attitude_and_the_onset(spec, cells, tmp_path):
    camp = _campaign(spec, "pd", [tmp_path / "a.toml"], 10, [0])
    sample = camp["sample"]
    keys = {f"plant.initial_attitude_deg.{i}.{k}" for i in range(4) for k in range(3)}
    assert keys <= set(sample) and all(
        sample[k]["std"] == 10.0 and sample[k]["mean"] == 0.0 for k in keys
    )
    assert sample["actuator.onset"] == {"dist": "uniform", "low": 100.0, "high": 150.0}
    # the sampled paths set the plant's initial Euler angles of a cell (what the campaign does per run)
    raw = copy.deepcopy(cells["yang2013"][0].raw)
    draws = np.random.default_rng(0).normal(0.0, 10.0, size=(4, 3))
    for i in range(4):
        for k in range(3):
            set_dotted(raw, f"plant.initial_attitude_deg.{i}.{k}", float(draws[i, k]))
    set_dotted(raw, "actuator.onset", 123.0)
    sc = ftc.load_scenario(raw)
    plant, actuator = sc.section("plant"), sc.section("actuator")
    np.testing.assert_allclose(plant.initial_attitude_deg, draws, rtol=0, atol=0)
    np.testing.assert_allclose(np.rad2deg(plant.euler_angles()), draws, atol=1e-9)  # LVLH angles
    assert actuator.onset == 123.0


def _copy_league(tmp_path: Path, name: str) -> tuple[Path, dict]:
    src = builtin_leagues()[name]
    shutil.copytree(src.parent / "attitude", tmp_path / "attitude")
    shutil.copytree(src.parent / "translational", tmp_path / "translational")
    return tmp_path / src.name, tomllib.loads(src.read_text())


def test_unknown_method_scenario_file_is_rejected(tmp_path):
    path, raw = _copy_league(tmp_path, "attitude")
    raw["methods"].append({"name": "lqg", "scenario": "attitude/lqg.toml"})
    path.write_text(tomli_w.dumps(raw))
    with pytest.raises(
        LeagueError, match=r"methods\[lqg\]\.scenario = 'attitude/lqg\.toml': no such file"
    ):
        load_league(path)


def test_attitude_law_on_the_translational_truth_is_rejected(tmp_path):
    path, raw = _copy_league(tmp_path, "translational")
    pd = tomllib.loads((tmp_path / "attitude" / "pd.toml").read_text())
    del pd["tune"]  # its objective (control_impulse) is no translational metric: rejected first
    (tmp_path / "attitude" / "pd.toml").write_text(tomli_w.dumps(pd))
    raw["methods"].append({"name": "attitude-pd", "scenario": "attitude/pd.toml"})
    path.write_text(tomli_w.dumps(raw))
    spec = load_league(path)
    with pytest.raises(
        LeagueError,
        match="(?s)method attitude-pd cannot run cell none/unsaturated of league "
        "translational: .*controller attitude-pd commands a torque, "
        "but plant orbital-truth is driven by a force",
    ):
        plan_cells(spec, ["attitude-pd"])
