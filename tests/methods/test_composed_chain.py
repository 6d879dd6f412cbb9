"""Composition ``compose-azizi2009-on-li2020``: Azizi2009's relative-output chain law with LLFR
allocation and its HL supervisor on Li2020's four spacecraft (nonlinear LVLH relative motion about an
elliptic orbit, force-driven), through the chain sensors on the (N, 6) relative state and the
acceleration-to-force adapter."""

from __future__ import annotations

import copy
import dataclasses

import jax
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.cli import main
from formation_ftc.config import loader
from formation_ftc.config.loader import ScenarioError
from formation_ftc.core.polygon_formation import rotating_polygon
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.batch import batched_run, stack_params
from formation_ftc.sim.metrics import metrics_dict

NAME = "compose-azizi2009-on-li2020"
MASS = np.array([100.0, 120.0, 115.0, 108.0])
E_S = 0.03  # the supervisor's mission error bound in the scenario [m]


def _raw(**slots):
    raw = copy.deepcopy(loader.read_raw(NAME)[0])
    for slot, value in slots.items():
        if value is None:
            raw.pop(slot, None)
        else:
            raw[slot] = value
    return raw


def test_scenario_runs_records_metrics_check_fault_and_supervisor():
    scn = ftc.load_scenario(NAME, {"simulation.horizon": 70.0, "simulation.record_every": 100})
    ds, m = ftc.simulate_with_metrics(scn)
    for var in (
        "position",
        "velocity",
        "tracking_error",
        "desired_position",
        "mode",
        "mode_changes",
        "time_in_flfr",
        "flfr_settled",
        "command",
        "acceleration_command",
        "applied",
        "actuator_gain",
        "delta_v",
    ):
        assert var in ds, var
    assert ds.sizes["spacecraft"] == 4 and ds.sizes["pair"] == 3 and ds.sizes["time"] == 71
    assert ds.command.attrs["units"] == "N" and ds.acceleration_command.attrs["units"] == "m s-2"
    t = ds.time.values
    # metrics: the FLFR window (settle_time 20 s after the switch) lies beyond this 70 s run
    assert np.isnan(m.pop("max_err_after_flfr"))
    assert all(np.isfinite(v) for v in m.values()), m
    # truth side: satellite 2's x actuator at 80 % from 60 s on, every other channel at 100 %
    gain = ds.actuator_gain.values
    expected = np.ones_like(gain)
    expected[t >= 60.0, 1, 0] = 0.8
    np.testing.assert_array_equal(gain, expected)
    np.testing.assert_allclose(ds.applied.values, gain * ds.command.values, rtol=1e-14)
    # flight side: force = nominal mass x the law's acceleration
    np.testing.assert_allclose(
        ds.command.values, MASS[None, :, None] * ds.acceleration_command.values, rtol=1e-14
    )
    # the true chain errors are the measured ones of the sensors (exact): x_{i+1} - x_i minus the square's
    pos, des = ds.position.values, ds.desired_position.values
    np.testing.assert_allclose(
        ds.tracking_error.values, np.diff(pos, axis=1) - np.diff(des, axis=1), atol=1e-9
    )
    rd, _, _ = rotating_polygon(t[-1], 4, 3, 200.0, 0.1)
    np.testing.assert_allclose(des[-1], np.asarray(rd), atol=1e-9)
    # the square is acquired from Li2020's initial positions (~700 m chain errors) within e_s ...
    err = np.max(np.abs(ds.tracking_error.values), axis=(1, 2))
    assert err[0] > 600.0
    assert np.all(err[(t >= 40.0) & (t < 60.0)] < E_S)
    assert m["acquisition_time"] < 40.0
    # ... the supervisor goes Nominal -> LLFR when the estimate arrives (60 s) and LLFR -> FLFR only
    # after the fault pushes the chain errors above e_s (two events, none before the fault)
    mode = ds["mode"].values
    # a record at t_k holds the decision in force over [t_k, t_k+1): LLFR from the estimate's arrival at 60 s
    np.testing.assert_array_equal(mode[t < 60.0], 0)
    assert mode[np.flatnonzero(t >= 60.0)[0]] == 1
    assert 60.0 < m["t_flfr"] < 65.0 and m["n_events"] == 2.0
    np.testing.assert_array_equal(mode[t > m["t_flfr"]], 2)
    np.testing.assert_array_equal(ds.mode_changes.values[t > m["t_flfr"]], 2)
    assert (
        np.max(err[t > m["t_flfr"]]) > E_S
    )  # the deep-space FLFR design does not absorb the orbit
    assert all(c.holds for c in ftc.check(scn))


def test_deep_space_limit_reproduces_the_azizi2009_method():
    """With the orbit made negligible (a = 7e12 m), no disturbance and the spacecraft started on the
    square, the composition (nonlinear LVLH plant, forces = mass x acceleration) flies exactly
    Azizi2009's double-integrator closed loop (scenario azizi2009-flfr: other components for the plant
    and the sensors) with the FLFR weight designed there by eq. (11)."""
    horizon = 30.0
    az = ftc.load_scenario(
        "azizi2009-flfr",
        {
            "simulation.horizon": horizon,
            "simulation.dt": 0.01,
            "simulation.record_every": 10,
            "plant.disturbance_acceleration": "0",
        },
    )
    ds_a, m_a = ftc.simulate_with_metrics(az)
    rd, vd, _ = rotating_polygon(0.0, 4, 3, 200.0, 0.1)
    co = ftc.load_scenario(
        NAME,
        {
            "simulation.horizon": horizon,
            "simulation.record_every": 10,
            "plant.initial_position": np.asarray(rd).tolist(),
            "plant.initial_velocity": np.asarray(vd).tolist(),
            "plant.disturbance_force": ["0", "0", "0"],
            "reference.semi_major_axis": 7e12,
            "supervisor.estimate_time": 0.0,
            "supervisor.monitor_start": 0.0,
            "actuator.onset": 0.0,
        },
    )
    ds_c, m_c = ftc.simulate_with_metrics(co)
    designed = float(make_loop(az).controller.alpha_flfr)
    assert co.section("controller").alpha_flfr == pytest.approx(designed, rel=1e-12)
    e_a, e_c = ds_a.tracking_error.values, ds_c.tracking_error.values
    assert np.max(np.abs(e_a)) > E_S  # the fault does violate e_s (a non-trivial comparison)
    np.testing.assert_allclose(e_c, e_a, rtol=0, atol=1e-8)
    np.testing.assert_array_equal(ds_c["mode"].values, ds_a["mode"].values)
    np.testing.assert_allclose(
        ds_c.acceleration_command.values, ds_a.command.values, rtol=0, atol=1e-8
    )
    assert m_c["t_flfr"] == m_a["t_flfr"]
    assert m_c["max_err_after_flfr"] == pytest.approx(m_a["max_err_after_flfr"], rel=1e-6)


def test_flfr_reduces_the_post_fault_error_against_llfr_alone_but_not_below_e_s_in_orbit():
    """One vmapped program, two runs that differ only in the supervisor's FLFR flag (a leaf)."""
    scn = ftc.load_scenario(NAME, {"simulation.horizon": 100.0, "simulation.record_every": 100})
    loop = make_loop(scn)
    llfr_only = dataclasses.replace(
        loop, supervisor=dataclasses.replace(loop.supervisor, flfr=np.asarray(False))
    )
    batch, axes = stack_params([loop, llfr_only])
    out = jax.device_get(batched_run(loop, axes, 2)(batch))
    assert np.all(np.asarray(out["diverged_step"]) < 0)
    flfr, llfr = (
        metrics_dict(loop.metrics, [np.asarray(v)[b] for v in out["metrics"]]) for b in range(2)
    )
    assert flfr["n_events"] == 2.0 and llfr["n_events"] == 1.0 and np.isnan(llfr["t_flfr"])
    assert (
        flfr["max_err_before_fault"] == llfr["max_err_before_fault"] < E_S
    )  # identical until the switch
    assert flfr["max_err_after_fault"] < 0.75 * llfr["max_err_after_fault"]  # FLFR helps ...
    assert flfr["max_err_after_flfr"] > E_S  # ... but the orbit's unmodelled accelerations remain


_ATTITUDE_PLANT = {
    "type": "quaternion-rigid-body",
    "inertia": [25.0, 25.0, 25.0],
    "initial_attitude_deg": [[0.0, 0.0, 0.0]] * 4,
}


@pytest.mark.parametrize(
    "slots, needles",
    [
        (
            {"sensors": {"type": "relative-state"}},
            ("supervisor hierarchical needs relative positions", 'sensors type = "chain-relative"'),
        ),
        (
            {"sensors": None, "supervisor": None},
            (
                "controller azizi2009-llfr needs relative positions",
                'sensors type = "chain-relative"',
            ),
        ),
        (
            {"controller": {"type": "pd", "kp": 1.0, "kd": 1.0}},
            (
                "supervisor hierarchical needs a law whose allocation has the modes",
                "azizi2009-llfr",
            ),
        ),
        (
            {"plant": _ATTITUDE_PLANT, "reference": None, "supervisor": None, "actuator": None},
            ("controller azizi2009-llfr commands an acceleration", "plant quaternion-rigid-body"),
        ),
        (
            {
                "controller": {
                    "type": "azizi2009-llfr",
                    "lambda0": 2.0,
                    "lambda1": 3.0,
                    "side": 200.0,
                    "omega": 0.1,
                    "alpha": [1.0, 1.0, 1.0],
                }
            },
            ("controller.alpha", "4 spacecraft"),
        ),
        (
            {"actuator": {"type": "actuator-gains", "spacecraft": 5}},
            ("actuator.spacecraft", "4 spacecraft"),
        ),
    ],
)
def test_impossible_compositions_are_rejected_at_validation(slots, needles):
    with pytest.raises(ScenarioError) as err:
        ftc.load_scenario(_raw(**slots))
    for needle in needles:
        assert needle in str(err.value), (needle, str(err.value))


def test_flfr_needs_an_interior_faulty_spacecraft():
    with pytest.raises(ScenarioError, match="supervisor.flfr needs an interior faulty spacecraft"):
        ftc.load_scenario(NAME, {"controller.faulty_spacecraft": 1})


def test_cli_rejects_the_law_without_chain_sensors_with_exit_2(tmp_path, capsys):
    text = loader.builtin_scenarios()[NAME].replace(
        'type = "chain-relative"', 'type = "relative-state"'
    )
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "supervisor hierarchical needs" in err and 'sensors type = "chain-relative"' in err
