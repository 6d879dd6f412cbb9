"""Scenario validation: every bad input is rejected before any computation, naming the field."""

import json

import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.config.loader import ScenarioError, dump_toml, parse_override


@pytest.mark.parametrize(
    "overrides,fragment",
    [
        ({"controller.gain": 3.0}, "controller.gain: Extra inputs are not permitted"),
        ({"simulation.dt": "fast"}, "field simulation.dt"),
        (
            {"plant.mass": [100.0, -1.0, 1.0, 1.0]},
            "plant: mass: at least one spacecraft, every mass finite and > 0 kg",
        ),
        ({"simulation.dt": 0.7}, "must divide simulation.horizon"),
        ({"simulation.dt": 0.0}, "simulation.dt"),
        (
            {"plant.initial_position": [[0.0, 0.0, 0.0]]},
            "plant: initial_position: 1 rows for 4",
        ),
        ({"actuator.bias": ["0", "foo(t)", "0"]}, "unknown function 'foo'"),
        ({"actuator.bias": ["0", "t.__class__", "0"]}, "attribute"),
        ({"actuator.bias": ["0", "y*2", "0"]}, "unknown name 'y'"),
        ({"controller.type": "nope"}, "controller.type = 'nope' is not a controller type"),
        ({"scenario.method": "nope"}, "unknown method 'nope'"),
    ],
)
def test_bad_input_names_field(overrides, fragment):
    with pytest.raises(ScenarioError) as info:
        ftc.load_scenario("cw-pd-fault", overrides)
    assert fragment in str(info.value)


def test_unknown_scenario_lists_builtins(tmp_path):
    with pytest.raises(ScenarioError, match="cw-free-drift"):
        ftc.load_scenario("does-not-exist")
    with pytest.raises(ScenarioError, match="does not exist"):
        ftc.load_scenario(tmp_path / "x.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[scenario\nname=1")
    with pytest.raises(ScenarioError, match="invalid TOML"):
        ftc.load_scenario(bad)
    nometh = tmp_path / "nometh.toml"  # no method: the composed schema, which needs the slots
    nometh.write_text("[scenario]\nname='x'\n")
    with pytest.raises(ScenarioError, match="field simulation: Field required"):
        ftc.load_scenario(nometh)
    noscn = tmp_path / "noscn.toml"
    noscn.write_text("[simulation]\nhorizon = 1.0\n")
    with pytest.raises(ScenarioError, match=r"a \[scenario\] table is required"):
        ftc.load_scenario(noscn)
    raw = ftc.config.loader.read_raw("cw-pd-fault")[0]
    del raw["scenario"]["method"]  # the method line is optional
    assert ftc.load_scenario(raw).scenario.method == "composed"


def test_overrides_and_round_trip(tmp_path):
    scn = ftc.load_scenario(
        "cw-pd-fault",
        ["simulation.horizon=100", "controller.kp=3.5", 'actuator.bias=["0", "0.1", "0"]'],
    )
    assert scn.simulation.horizon == 100.0 and scn.section("controller").kp == 3.5
    path = tmp_path / "s.toml"
    path.write_text(dump_toml(scn))
    again = ftc.load_scenario(path)
    assert again == scn
    assert parse_override("a.b=hello") == ("a.b", "hello")
    with pytest.raises(ScenarioError):
        parse_override("novalue")


def test_result_records_provenance(tmp_path):
    scn = ftc.load_scenario("cw-pd-fault", {"simulation.horizon": 20.0})
    ds, metrics = ftc.simulate_with_metrics(scn)
    for key in (
        "scenario_toml",
        "seed",
        "git_commit",
        "version_jax",
        "version_numpy",
        "metrics_json",
    ):
        assert key in ds.attrs, key
    paths = ftc.save_result(ds, tmp_path)
    import xarray as xr

    back = xr.open_dataset(paths["result"], engine="h5netcdf")
    np.testing.assert_array_equal(back.position.values, ds.position.values)
    assert back.attrs["scenario_name"] == "cw-pd-fault"
    m = json.loads(paths["metrics"].read_text())
    assert m["scenario"] == "cw-pd-fault" and m["delta_v_total"] == pytest.approx(
        metrics["delta_v_total"]
    )
