"""Numeric step fault profile (actuator type "step-faults") used by Monte Carlo campaigns."""

import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.config.loader import ScenarioError

BASE = {"simulation.horizon": 30.0}
EFF = [[0.5, 1.0, 1.0], [1.0, 0.6, 1.0], [1.0, 1.0, 0.7], [0.4, 0.4, 0.4]]
ONSET = [[10.0, 0.0, 0.0], [0.0, 15.0, 0.0], [0.0, 0.0, 20.0], [5.0, 5.0, 5.0]]


def _step(effectiveness=EFF, onset=ONSET) -> dict:
    """Overrides that replace the expression faults by the step profile (as the campaign does)."""
    return {
        **BASE,
        "actuator.type": "step-faults",
        "actuator.effectiveness": effectiveness,
        "actuator.onset": onset,
    }


def _as_expressions():
    # the same profile written as expressions in t and i (an independent code path)
    cols = []
    for j in range(3):
        terms = " ".join(
            f"+ (i == {i + 1}) * where(t >= {ONSET[i][j]}, {EFF[i][j]}, 1)" for i in range(4)
        )
        cols.append(terms[2:])
    return cols


@pytest.mark.parametrize(
    "scenario,atol",
    [
        # SIR-FTC is smooth: the two code paths agree to round-off
        ("li2020-sirftc", 1e-9),
        # Thm 1 has a stiff episode near t = 2 s at dt = 0.01 s that amplifies round-off differences
        # (operation order) to ~1e-4 m (notes of issue 3); 1e-3 m is still 5e-7 of the 500 m formation
        ("li2020-thm1", 1e-3),
    ],
)
def test_step_profile_equals_expression_profile(scenario, atol):
    step = ftc.simulate(ftc.load_scenario(scenario, _step()))
    expr = ftc.simulate(
        ftc.load_scenario(scenario, {**BASE, "actuator.effectiveness": _as_expressions()})
    )
    np.testing.assert_array_equal(step.effectiveness.values, expr.effectiveness.values)
    np.testing.assert_allclose(step.position.values, expr.position.values, rtol=0, atol=atol)


def test_step_profile_shares_one_program_across_values():
    from formation_ftc.api import build_loop

    a = build_loop(ftc.load_scenario("li2020-thm1", _step()))
    b = build_loop(ftc.load_scenario("li2020-thm1", _step([[0.9] * 3] * 4, [[1.0] * 3] * 4)))
    assert a.static_key == b.static_key
    assert not np.array_equal(a.actuator.effectiveness, b.actuator.effectiveness)


@pytest.mark.parametrize(
    "field,value,msg",
    [
        ("effectiveness", [[0.0, 1.0, 1.0]] * 4, "effectiveness[0][0] = 0.0: must be (0, 1]"),
        ("effectiveness", [[1.0, 1.0, 1.2]] * 4, "must be (0, 1]"),
        ("onset", [[-1.0, 0.0, 0.0]] * 4, "onset[0][0] = -1.0: must be >= 0"),
        ("onset", [[0.0, 0.0, 0.0]] * 3, "actuator.onset: 3 rows for 4 spacecraft"),
    ],
)
def test_bad_step_profile(field, value, msg):
    with pytest.raises(ScenarioError) as info:
        ftc.load_scenario("li2020-thm1", {**_step(), f"actuator.{field}": value})
    assert msg in str(info.value)
