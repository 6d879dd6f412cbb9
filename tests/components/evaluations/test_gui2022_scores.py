"""Gui2022's evaluation (``gui2022-scores``): the signal arithmetic it is made of against numpy, and the
loop refused, naming the part and the provider, without the observer whose records it scores."""

import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components.evaluations._signal_arithmetic import PartNorm, SignalSum
from formation_ftc.config import loader


def test_signal_sum_and_part_norm():
    rng = np.random.default_rng(4)
    a, b, c = (rng.normal(size=(2, 6)) for _ in range(3))
    s = SignalSum("h", (("+", "a"), ("-", "b"), ("+", "c"))).outputs({"a": a, "b": b, "c": c})["h"]
    np.testing.assert_allclose(s, a - b + c, rtol=1e-15)
    neg = SignalSum("h", (("-", "a"),)).outputs({"a": a})["h"]
    np.testing.assert_array_equal(neg, -a)
    pn = PartNorm("p", "a", 3, 6).outputs({"a": a})["p"]
    np.testing.assert_allclose(pn, np.linalg.norm(a[:, 3:], axis=1), rtol=1e-15)
    with pytest.raises(ValueError, match="sign"):
        SignalSum("h", (("*", "a"),))


def test_scores_without_the_observer_are_refused():
    raw = loader.read_raw("gui2022-ilo")[0]
    del raw["estimator"]
    with pytest.raises(loader.ScenarioError) as err:
        ftc.load_scenario(raw)
    msg = str(err.value)
    # (the part is labelled by its place in the loop's evaluations, after those the builders add)
    assert "Gui2022Scores needs an estimate F_hat" in msg or "gui2022-scores needs" in msg, msg
    assert 'estimator type = "iterative-learning-observer"' in msg, msg
