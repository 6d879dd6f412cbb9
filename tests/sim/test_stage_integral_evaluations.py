"""Stage-integrated metrics of an evaluation's signal (the applied force per unit mass).

Oracle: the plant's own ``delta_v`` usage integral, which the loop integrates *with the state* (RK4
weights of ||command|| / m at the four stages) -- a different code path from the metric accumulator.
With an ideal actuator the applied force is the command, so the stage integral of the evaluation's
``applied_acceleration`` must equal it to rounding (1e-10 relative); a step-sampled (rectangle rule)
integral of the same signal may not, and a thruster fault must make the applied integral move away
from the commanded one.
"""

from __future__ import annotations

import numpy as np

from formation_ftc.api import load_scenario, simulate_with_metrics

SCENARIO = """
[scenario]
name = "stage-integral-check"
method = "composed"

[simulation]
horizon = 60.0
dt = 0.5
record_every = 120

[plant]
type = "clohessy-wiltshire"
semi_major_axis = 7000e3
mass = [100.0, 120.0]
initial_position = [[30.0, 0.0, 5.0], [-20.0, 10.0, 0.0]]

[controller]
type = "lqr"
semi_major_axis = 7000e3
nominal_mass = [100.0, 120.0]
max_position_error = 10.0
max_velocity_error = 1.0
max_acceleration = 1.0
desired_position = ["0", "0", "0"]
{actuator}
[[evaluations]]
type = "formation-scores"
desired = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]

[[metrics]]
name = "dv_commanded"
signal = "delta_v"
reduce = "last"
spacecraft = "each"
units = "m s-1"

[[metrics]]
name = "dv_applied_stage"
signal = "applied_acceleration"
reduce = "stage_integral"
spacecraft = "each"
units = "m s-1"

[[metrics]]
name = "dv_applied_rectangle"
signal = "applied_acceleration"
reduce = "integral"
spacecraft = "each"
units = "m s-1"
"""

BIAS = """
[actuator]
type = "thruster-bias"
onset = [10.0, 0.0, 0.0]
magnitude = [0.5, 0.0, 0.0]
"""


def _metrics(tmp_path, actuator: str) -> dict[str, np.ndarray]:
    path = tmp_path / "s.toml"
    path.write_text(SCENARIO.replace("{actuator}", actuator))
    _, m = simulate_with_metrics(load_scenario(path))
    return {
        k: np.array([m[f"{k}_sc1"], m[f"{k}_sc2"]])
        for k in ("dv_commanded", "dv_applied_stage", "dv_applied_rectangle")
    }


def test_stage_integral_of_applied_acceleration_equals_the_plants_usage_integral(tmp_path):
    m = _metrics(tmp_path, "")
    assert np.all(m["dv_commanded"] > 0.1)  # the law works: a few m/s to acquire 30 m
    np.testing.assert_allclose(m["dv_applied_stage"], m["dv_commanded"], rtol=1e-10)
    # the rectangle rule samples the command at each step's start only: a different number
    assert not np.allclose(m["dv_applied_rectangle"], m["dv_commanded"], rtol=1e-6)


def test_a_thruster_bias_separates_applied_from_commanded_delta_v(tmp_path):
    m = _metrics(tmp_path, BIAS)
    # 0.5 N radial bias on every spacecraft after 10 s: the applied integral is not the commanded one
    assert np.all(np.abs(m["dv_applied_stage"] - m["dv_commanded"]) > 1e-3)
    assert np.all(np.isfinite(m["dv_applied_stage"]))
