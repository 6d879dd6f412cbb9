"""Signal temporal logic requirements: the robustness against rtamt's discrete-time offline monitor
(an independent implementation) at every sample of constructed signals, the worst spacecraft of a
vector atom, parse errors naming the position, and a compiled run whose in-run robustness equals the
monitor's on the recorded signal."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from formation_ftc import api
from formation_ftc.config import loader
from formation_ftc.sim.stl import StlError, _rho, parse, robustness, signals_of

rtamt = pytest.importorskip("rtamt")

#: ours -> rtamt's syntax of the same formula
FORMULAS = {
    "G[0,5](x <= 1)": "always[0:5](x <= 1)",
    "F[2,7](x >= 0.5)": "eventually[2:7](x >= 0.5)",
    "F[0,10](G[0,5](x <= 1))": "eventually[0:10](always[0:5](x <= 1))",
    "G(x <= 2)": "always(x <= 2)",
    "F(y > 1.5)": "eventually(y > 1.5)",
    "G[0,30](x >= 1 -> F[0,3](y <= 0))": "always[0:30]((x >= 1) implies (eventually[0:3](y <= 0)))",
    "not (x <= 0) and y >= -1 or x >= 1": "((not (x <= 0)) and (y >= -1)) or (x >= 1)",
    "G(F[0,4](x >= 0) & !(y < -2))": "always((eventually[0:4](x >= 0)) and (not (y < -2)))",
}


def _rtamt(formula: str, signals: dict[str, np.ndarray], step: float) -> np.ndarray:
    spec = rtamt.StlDiscreteTimeSpecification()
    for name in signals:
        spec.declare_var(name, "float")
    spec.set_sampling_period(step, "s", 0.1)
    spec.spec = formula
    spec.parse()
    n = len(next(iter(signals.values())))
    data = {"time": [k * step for k in range(n)], **{k: list(v) for k, v in signals.items()}}
    return np.array([v for _, v in spec.evaluate(data)])


@pytest.mark.parametrize("ours", list(FORMULAS))
def test_robustness_equals_rtamt_at_every_sample(ours):
    """40 random samples 0.5 s apart (bounds in seconds: a window of [2, 7] s is samples 4 .. 14):
    the robustness series equals rtamt's to 1e-12 (both are exact min/max of the same numbers)."""
    rng = np.random.default_rng(len(ours))
    signals = {"x": rng.normal(size=40), "y": rng.normal(size=40)}
    step = 0.5
    theirs = _rtamt(FORMULAS[ours], signals, step)
    mine = np.asarray(_rho(parse(ours), signals, step))
    np.testing.assert_allclose(mine, theirs, rtol=0, atol=1e-12)
    assert float(robustness(parse(ours), signals, step)) == pytest.approx(theirs[0], abs=1e-12)


def test_a_vector_atom_holds_for_its_worst_spacecraft():
    x = np.array([[0.5, 0.9], [0.2, 1.4], [0.1, 0.3]])  # (samples, spacecraft)
    assert float(robustness(parse("G(x <= 1)"), {"x": x}, 1.0)) == pytest.approx(-0.4)
    assert float(robustness(parse("G(x >= 0)"), {"x": x}, 1.0)) == pytest.approx(0.1)
    assert signals_of(parse("G(x <= 1) -> F(y >= 2)")) == {"x", "y"}


@pytest.mark.parametrize(
    ("text", "where"),
    [
        ("G(x <=)", "position 6"),
        ("G[5,1](x <= 1)", "needs 0 <= a <= b"),
        ("F[0,3](x == 1)", "position 9"),
        ("x <= 1 )", r"unexpected '\)'"),
        ("", "empty"),
        ("G(and <= 1)", "expected a signal"),
        ("x # 1", "unexpected character"),
    ],
)
def test_a_formula_that_does_not_parse_names_where(text, where):
    with pytest.raises(StlError, match=where):
        parse(text)


def _scenario(formula: str) -> dict:
    raw, _ = loader.read_raw("cw-lqr-navigation-filter")
    raw = copy.deepcopy(raw)
    raw["simulation"]["horizon"] = 400.0
    raw["metrics"].append({"name": "req", "reduce": "stl", "formula": formula, "units": "m"})
    return raw


def test_in_run_robustness_equals_the_monitor_on_the_records():
    """The requirement is computed inside the compiled run from the records; the recorded signal
    given to rtamt gives the same number (to 1e-12)."""
    formula = "F[0,200](G(nees <= 2))"
    ds, metrics = api.simulate_with_metrics(loader.validate(_scenario(formula), "stl"))
    nees = np.asarray(ds["nees"].values, dtype=float)  # (records, spacecraft)
    step = float(ds["time"].values[1] - ds["time"].values[0])
    worst = nees.max(axis=1)
    theirs = _rtamt("eventually[0:200](always(nees <= 2))", {"nees": worst}, step)
    assert metrics["req"] == pytest.approx(theirs[0], abs=1e-12)


@pytest.mark.parametrize(
    ("metric", "message"),
    [
        ({"name": "r", "reduce": "stl"}, "needs an STL formula"),
        ({"name": "r", "signal": "nees", "reduce": "max", "formula": "G(nees <= 1)"}, "only with"),
        ({"name": "r", "reduce": "stl", "formula": "G(nees <= )"}, "position 10"),
        ({"name": "r", "reduce": "stl", "formula": "G(nope <= 1)"}, "'nope', not recorded"),
    ],
)
def test_bad_requirements_are_named(metric, message):
    raw, _ = loader.read_raw("cw-lqr-navigation-filter")
    raw = copy.deepcopy(raw)
    raw["metrics"].append(metric)
    with pytest.raises(Exception, match=message):
        api.build_loop(loader.validate(raw, "stl"))
