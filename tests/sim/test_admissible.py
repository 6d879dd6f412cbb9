"""Divergence means leaving the admissible set, dated to the exact step, whatever the record block."""

from __future__ import annotations

import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.cli import main
from formation_ftc.components.plants.clohessy_wiltshire import rk4_amplification

STIFF = {
    "controller.kd": 3000.0,
    "simulation.horizon": 20.0,
    "sensors.position_noise_std": 0.0,
    "sensors.velocity_noise_std": 0.0,
    "plant.process_noise_std": 0.0,
}


def _diverge(record_every: int):
    scn = ftc.load_scenario("cw-pd-fault", {**STIFF, "simulation.record_every": record_every})
    with pytest.raises(ftc.SimulationDiverged) as err:
        ftc.simulate(scn)
    return err.value


def test_stiff_gain_leaves_the_admissible_set_long_before_overflow():
    err = _diverge(1)  # recorded at every step (the program of the two tests below)
    info = err.info
    assert info.variable.startswith("plant.velocity") and "admissible" in str(err)
    # |R(lambda dt)| = 1.375 per step from ~80 m/s: 1e4 m/s is passed after a few dozen steps,
    # far before the 3e80 m the unbounded run reached
    assert 1.0 < info.time < 10.0
    v = np.linalg.norm(err.partial.velocity.values, axis=-1)
    assert np.all(np.isfinite(v)) and v.max() <= 1e4


def test_divergence_time_does_not_depend_on_the_record_block():
    fine = _diverge(1).info
    coarse = _diverge(200).info  # one record block for the whole run
    assert coarse.step == fine.step and coarse.time == pytest.approx(fine.time, abs=1e-12)
    assert coarse.variable == fine.variable and coarse.spacecraft == fine.spacecraft


def test_admissible_bound_is_a_scenario_field():
    scn = ftc.load_scenario(
        "cw-pd-fault",
        {
            **STIFF,
            "simulation.max_velocity": 1e30,
            "simulation.max_position": 1e30,
            "simulation.record_every": 1,  # the program of the tests above
        },
    )
    ds = ftc.simulate(scn)  # the same run stays "admissible" up to its 20 s with huge bounds
    assert np.isfinite(ds.position.values).all()


def test_rk4_amplification_against_the_stability_boundary():
    # the real-axis RK4 stability limit is z = -2.785293563...; |R| = 1 there, < 1 inside, > 1 outside
    z0 = -2.7852935634
    assert rk4_amplification(z0) == pytest.approx(1.0, abs=1e-9)
    assert rk4_amplification(z0 + 0.01) < 1.0 < rk4_amplification(z0 - 0.01)
    # the imaginary-axis limit is 2 sqrt(2)
    assert rk4_amplification(2j * np.sqrt(2)) == pytest.approx(1.0, abs=1e-12)


def test_check_uses_closed_loop_eigenvalues(capsys):
    assert main(["check", "cw-pd-fault", "--set", "controller.kd=3000", "--json"]) == 1
    import json

    out = json.loads(capsys.readouterr().out)
    row = next(c for c in out["conditions"] if c["name"] == "RK4 step vs closed-loop modes")
    assert row["holds"] is False and "1.375" in row["value_text"]
    assert main(["check", "cw-pd-fault", "--json"]) == 0


def test_body_rate_bound_is_part_of_the_admissible_set_and_overridable():
    """A constant 5 N m torque on a 25 kg m^2 body spins it up at 0.2 rad/s^2: with max_rate = 0.5 rad/s
    the run leaves its admissible set at about 2.5 s (the attitude plants report their body rates)."""
    scn = ftc.load_scenario(
        "compose-mehrabian-on-yang2013",
        {
            "simulation.horizon": 10.0,
            "simulation.max_rate": 0.5,
            "plant.disturbance_torque": ["5.0", "0", "0"],
        },
    )
    with pytest.raises(ftc.SimulationDiverged) as err:
        ftc.simulate(scn)
    assert err.value.info.variable.startswith("plant.angular_rate")
    assert 1.0 < err.value.info.time < 4.0
    # the default bound (100 rad/s) lets the same run finish (the bound is a leaf: the same program)
    ftc.simulate(
        ftc.load_scenario(
            "compose-mehrabian-on-yang2013",
            {"simulation.horizon": 10.0, "plant.disturbance_torque": ["5.0", "0", "0"]},
        )
    )


def test_metrics_of_a_diverged_run_stop_at_the_failing_block():
    """A run that leaves its admissible set keeps the metrics accumulated up to the start of the failing
    record block (the state it returns) and takes no horizon sample: with a record every step, the
    maximum and the last in-window value are those of the records before the failing step."""
    import json

    err = _diverge(1)
    ds, step = err.partial, err.info.step
    metrics = json.loads(ds.attrs["metrics_json"])
    # records 0 .. step: the state at the failing step's start is the last record kept
    assert ds.sizes["time"] == step + 1
    e = np.linalg.norm(ds.position_error.values, axis=-1)  # (time, spacecraft)
    assert metrics["max_position_error"] == pytest.approx(e[:step].max(axis=1).max(), rel=1e-12)
    assert metrics["final_position_error_mean"] == pytest.approx(e[step - 1].mean(), rel=1e-12)
    assert metrics["final_position_error_mean"] != pytest.approx(e[step].mean(), rel=1e-6)


_LIMITS = {
    "simulation.max_position": 123.0,
    "simulation.max_velocity": 4.5,
    "simulation.max_rate": 6.7,
    "simulation.max_pitch": 1.2,
}


@pytest.mark.parametrize("name", sorted(ftc.list_scenarios()))
def test_every_builder_takes_the_admissible_set_from_the_simulation_section(name):
    """The loop of every built-in scenario -- through the API and through its method's own builder,
    which the paper reproductions call directly -- carries ``[simulation]``'s admissible set
    (:meth:`ClosedLoop.from_simulation`), not the loop's defaults."""
    from formation_ftc.api import build_loop
    from formation_ftc.registry import get_method

    scn = ftc.load_scenario(name, _LIMITS)
    loops = [build_loop(scn), get_method(scn.scenario.method).build(scn)]
    for loop in loops:
        got = [
            float(loop.max_position),
            float(loop.max_velocity),
            float(loop.max_rate),
            float(loop.max_pitch),
        ]
        assert got == list(_LIMITS.values())
        assert loop.dt == scn.simulation.dt and loop.n_steps == scn.simulation.n_steps
