"""The ``composed`` method: components named in a scenario file, checked before any computation."""

from __future__ import annotations

import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.cli import main
from formation_ftc.config.loader import ScenarioError

SHORT = {"simulation.horizon": 40.0, "simulation.record_every": 100}


def test_li2020_law_on_cw_runs_records_metrics_and_check():
    scn = ftc.load_scenario("compose-li2020-on-cw", {**SHORT, "actuator.onset": [20.0, 0.0, 30.0]})
    ds, m = ftc.simulate_with_metrics(scn)
    for var in ("position", "position_error", "command", "applied", "fault", "m_hat", "delta_v"):
        assert var in ds, var
    assert ds.sizes["spacecraft"] == 4 and ds.sizes["time"] == 41
    # the truth-side fault is applied after its onset and only there (0.5 m/s^2 times each mass on x)
    fault_x = ds.fault.sel(axis="x").values
    t = ds.time.values
    np.testing.assert_allclose(fault_x[t < 20.0], 0.0)
    np.testing.assert_allclose(
        fault_x[t >= 20.0],
        np.broadcast_to(0.5 * np.array([100.0, 120.0, 115.0, 108.0]), fault_x[t >= 20.0].shape),
        rtol=1e-12,
    )
    np.testing.assert_allclose(ds.applied.values - ds.command.values, ds.fault.values, atol=1e-9)
    # every metric is finite except the one whose window (from 1000 s) lies beyond this 40 s run
    assert np.isnan(m.pop("max_position_error_after_1000s"))
    assert all(np.isfinite(v) for v in m.values())
    # the adaptive law pulls the formation in from ~500 m initial errors
    e = np.linalg.norm(ds.position_error.values, axis=-1).mean(axis=1)
    assert e[-1] < 0.5 * e[0]
    # the law's Thm 1 conditions apply: all hold but the balance of Li2020's printed graph (E000-07)
    conds = {c.name: c.holds for c in ftc.check(scn)}
    assert conds.pop("communication graph balanced") is False and "k_i > 0" in conds
    assert all(conds.values())


def test_cw_plant_in_a_composition_matches_cw_closed_form():
    """Free drift (zero command through a PD with zero gains) on the composed CW plant equals the CW
    closed-form solution (an independent truth)."""
    from formation_ftc.core.dynamics.cw import cw_closed_form

    raw = {
        "scenario": {"name": "drift", "method": "composed"},
        "simulation": {"horizon": 600.0, "dt": 1.0, "record_every": 60},
        "plant": {
            "type": "clohessy-wiltshire",
            "semi_major_axis": 7000e3,
            "mass": [10.0, 10.0],
            "initial_position": [[10.0, 0.0, 0.0], [0.0, 5.0, 1.0]],
            "initial_velocity": [[0.0, 0.01, 0.0], [0.001, 0.0, 0.0]],
        },
        "controller": {"type": "pd", "kp": 0.0, "kd": 0.0, "nominal_mass": 0.0},
    }
    ds = ftc.simulate(ftc.load_scenario(raw))
    n = np.sqrt(3.986004418e14 / 7000e3**3)
    q0 = np.array([[10.0, 0.0, 0.0, 0.0, 0.01, 0.0], [0.0, 5.0, 1.0, 0.001, 0.0, 0.0]])
    for k, t in enumerate(ds.time.values):
        exact = np.stack([cw_closed_form(n, q0[i], t)[0] for i in range(2)])
        np.testing.assert_allclose(ds.position.values[k], exact[:, :3], rtol=0, atol=1e-9)


def _raw(**slots):
    base = {
        "scenario": {"name": "bad", "method": "composed"},
        "simulation": {"horizon": 10.0, "dt": 0.1},
        "plant": {
            "type": "clohessy-wiltshire",
            "semi_major_axis": 7000e3,
            "mass": [10.0, 10.0],
            "initial_position": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        },
        "controller": {"type": "pd", "kp": 1.0, "kd": 1.0},
    }
    base.update(slots)
    return base


@pytest.mark.parametrize(
    "slots, needle",
    [
        (
            {
                "network": {
                    "type": "delayed-graph",
                    "adjacency": [[0, 1], [1, 0]],
                    "delays": [["1", "1"], ["1", "1"]],
                    "max_delay": 1.0,
                }
            },
            "controller pd exchanges none",
        ),
        (
            {"network": {"type": "graph", "adjacency": [[0, 1, 0], [1, 0, 0], [0, 0, 0]]}},
            "network.adjacency: must be 2x2 (one row/column per spacecraft), got 3x3",
        ),
        (
            {
                "plant": {
                    "type": "relative-lvlh",
                    "mass": [10.0],
                    "initial_position": [[1.0, 0.0, 0.0]],
                }
            },
            "reference",
        ),
        ({"controller": {"type": "no-such-law"}}, "controller.type"),
        ({"controller": {"type": "pd", "kp": -1.0, "kd": 1.0}}, "controller.kp"),
        ({"actuator": {"type": "thruster-bias", "onset": [1.0, 2.0]}}, "actuator.onset"),
    ],
)
def test_incompatible_compositions_are_rejected_at_validation(slots, needle):
    with pytest.raises(ScenarioError) as err:
        ftc.load_scenario(_raw(**slots))
    assert needle in str(err.value)


def test_cli_rejects_a_bad_composition_with_exit_2(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text("""
[scenario]
name = "bad"
method = "composed"
[simulation]
horizon = 10.0
dt = 0.1
[plant]
type = "clohessy-wiltshire"
semi_major_axis = 7000e3
mass = [10.0, 10.0]
initial_position = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
[controller]
type = "pd"
kp = 1.0
kd = 1.0
[network]
type = "delayed-graph"
adjacency = [[0, 1], [1, 0]]
delays = [["1", "1"], ["1", "1"]]
max_delay = 1.0
""")
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "network delayed-graph" in err and "controller pd" in err
