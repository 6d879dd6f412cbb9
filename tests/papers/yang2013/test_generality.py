"""The switched-formation composition on a formation that is not the paper's: 4 spacecraft, 3 modes, a departure with
a simultaneous arrival, then the departed spacecraft returning as a new state (Sec. 2.4, item 4).
Truth: the variation model (10) applied by hand to the pre-switch state (kept in the final carry)
and the decoupled closed-loop error ODE (each slot follows its own closed form without disturbance).
"""

import copy
import json

import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.registry import get_method

RAW = {
    "scenario": {"name": "yang2013-general-test", "method": "composed", "paper": "yang2013"},
    "simulation": {"horizon": 30.0, "dt": 0.05, "record_every": 10},
    "plant": {
        "type": "switched-formation",
        "count": 4,
        "rotation_coupling": False,
        "initial_state": [
            {"spacecraft": 1, "e_R": [0.1, 0.0, 0.0]},
            {"spacecraft": 2, "e_V": [0.0, 0.2, 0.0]},
        ],
    },
    "sensors": {"type": "tracking-error"},
    "controller": {"type": "yang2013-force-torque", "K1": 0.5, "K2": 0.8},
    "actuator": {"type": "velocity-gain-fault"},
    "estimator": {"type": "scheduled-diagnosis"},
    "supervisor": {
        "type": "switching",
        "modes": [
            {"name": "a", "start": 0.0, "members": [1, 2]},
            {
                "name": "b",
                "start": 10.0,
                "members": [1, 3],
                "variation": [[1.0, 0.0]],
                "new_states": [{"spacecraft": 3, "e_R": [0.0, 0.0, 0.1]}],
            },
            {
                "name": "c",
                "start": 20.0,
                "members": [1, 3, 2],
                "variation": [[1.0, 0.0], [0.0, 1.0]],
                "new_states": [{"spacecraft": 2, "e_R": [-0.05, 0.0, 0.0]}],
            },
        ],
    },
    "evaluations": [{"type": "switch-norms"}],
}


def closed_form(e0, v0, K1, K2, t):
    lam = np.roots([1.0, K2, K1 + 1.0])
    # e = c1 exp(l1 t) + c2 exp(l2 t)
    c = np.linalg.solve(np.array([[1, 1], [lam[0], lam[1]]]), np.array([e0, v0], dtype=complex))
    return np.real(c[0] * np.exp(lam[0] * t) + c[1] * np.exp(lam[1] * t))


def test_general_mode_sequence_with_return(tmp_path):
    sc = ftc.load_scenario(RAW)
    assert [len(m.members) for m in sc.section("supervisor").modes] == [2, 2, 3]
    ds = ftc.simulate(sc)
    x = ds["error_state"]
    # spacecraft 2 leaves at 10 s, returns at 20 s with its new state X*
    assert np.all(x.sel(time=10.0, spacecraft=2).values == 0)
    np.testing.assert_array_equal(x.sel(time=20.0, spacecraft=2).values[:3], [-0.05, 0, 0])
    np.testing.assert_array_equal(x.sel(time=10.0, spacecraft=3).values[:3], [0, 0, 0.1])
    assert ds["active"].sel(time=15.0).values.tolist() == [1, 0, 1, 0]
    assert ds["active"].sel(time=25.0).values.tolist() == [1, 1, 1, 0]
    # spacecraft 1 is never reset: it follows the closed form over the whole run
    t = ds["time"].values
    np.testing.assert_allclose(
        x.sel(spacecraft=1, component="e_R_x").values, closed_form(0.1, 0.0, 0.5, 0.8, t), atol=1e-7
    )
    # returning spacecraft 2 follows the closed form from its new state
    late = t >= 20.0
    np.testing.assert_allclose(
        x.sel(spacecraft=2, component="e_R_x").values[late],
        closed_form(-0.05, 0.0, 0.5, 0.8, t[late] - 20.0),
        atol=1e-7,
    )
    # |X(t_k)|^2 = |S X(t_k^-)|^2 + |X*|^2 (10), with S = [1, 0] at 10 s
    m = json.loads(ds.attrs["metrics_json"])
    pre_sc = [m[f"pre_switch_sc_norm_2_sc{s}"] for s in (1, 2)]
    assert m["post_switch_norm_2"] == pytest.approx(np.hypot(pre_sc[0], 0.1), rel=1e-12)
    # the left limit is the state the closed loop reached before the switch (recorded at 9.5 s + 0.5 s)
    assert pre_sc[1] > 0 and m["pre_switch_norm_2"] == pytest.approx(np.hypot(*pre_sc), rel=1e-12)
    paths = get_method("composed").plot(ds, sc, tmp_path)  # the paper's figure ([scenario] paper)
    assert [p.name for p in paths] == ["yang2013-general-test.png"]
    assert paths[0].stat().st_size > 10_000


def test_inactive_fault_is_not_diagnosed_before_joining():
    raw = copy.deepcopy(RAW)
    raw["actuator"]["faults"] = [{"spacecraft": 4, "onset": 5.0, "K2_faulty": -0.1}]
    ds, metrics = ftc.simulate_with_metrics(ftc.load_scenario(raw))
    assert metrics["supervisor_decision_sc4"] == 0  # spacecraft 4 never joins: no decision
    assert np.isnan(ds["supervisor_decision_time"].values[-1, 3])
