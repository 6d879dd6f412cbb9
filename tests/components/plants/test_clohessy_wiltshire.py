"""Plant ``clohessy-wiltshire``: the conditions of a linear state feedback on it (the ``pd`` and ``none``
controllers' ``conditions``): closed-loop stability per spacecraft and the RK4 step, against the
closed-form modes of the CW model; no linear condition on another plant."""

from __future__ import annotations

import math

import formation_ftc as ftc

A_ORBIT = 7000e3


def _names(conditions):
    return [c.name for c in conditions if c.name != "components fit together"]


def test_pd_on_cw_states_stability_per_spacecraft_and_the_rk4_step():
    conds = ftc.check(ftc.load_scenario("cw-pd-fault"))
    names = _names(conds)
    assert names == [f"closed-loop stable, spacecraft {i}" for i in range(1, 5)] + [
        "RK4 step vs closed-loop modes"
    ]
    assert all(c.holds for c in conds)


def test_zero_gains_leave_the_marginal_cw_modes():
    """kp = kd = 0: the closed loop is the free CW motion, eigenvalues 0, 0, +-i n, +-i n (Re = 0):
    not stable (the real part is not below the rounding margin)."""
    conds = ftc.check(
        ftc.load_scenario("cw-pd-fault", {"controller.kp": 0.0, "controller.kd": 0.0})
    )
    stable = [c for c in conds if c.name.startswith("closed-loop stable")]
    assert len(stable) == 4 and not any(c.holds for c in stable)
    n = math.sqrt(3.986004418e14 / A_ORBIT**3)
    # the RK4 step integrates the undamped modes (|lambda dt| = n dt << 2 sqrt(2)): no stable mode
    rk4 = next(c for c in conds if c.name == "RK4 step vs closed-loop modes")
    assert rk4.holds and f"{0.1 * n:.3g}" in rk4.value


def test_no_control_on_cw_states_the_rk4_step_of_the_free_modes():
    raw = {
        "scenario": {"name": "free", "method": "composed"},
        "simulation": {"horizon": 10.0, "dt": 0.1},
        "plant": {
            "type": "clohessy-wiltshire",
            "semi_major_axis": A_ORBIT,
            "mass": [100.0],
            "initial_position": [[1.0, 0.0, 0.0]],
        },
        "controller": {"type": "none"},
    }
    assert _names(ftc.check(ftc.load_scenario(raw))) == ["RK4 step vs closed-loop modes"]
    # on a plant without a linear model (relative-lvlh): no linear condition
    raw["plant"] = {**raw["plant"], "type": "relative-lvlh"}
    del raw["plant"]["semi_major_axis"]
    raw["reference"] = {"type": "keplerian", "semi_major_axis": A_ORBIT}
    raw["controller"] = {"type": "pd", "kp": 1.0, "kd": 10.0}
    assert _names(ftc.check(ftc.load_scenario(raw))) == []
