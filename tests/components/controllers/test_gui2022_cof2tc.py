"""Gui2022's COF2TC baseline (``gui2022-cof2tc``): the law against its formula, and the compositions the
loop refuses, naming the part, what it needs and who provides it: fault compensation without a fault
estimate, no on-board mean motion (no [reference] orbit, none stated)."""

import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components.controllers.gui2022_cof2tc import cof2tc_law
from formation_ftc.config import loader


def test_cof2tc_law_against_its_formula():
    """u = K e_y, and u = K e_y - B^+H F_hat with fault compensation."""
    rng = np.random.default_rng(5)
    e_y, F = rng.normal(size=(3, 6)), rng.normal(size=(3, 3))
    K, BpH = rng.normal(size=(3, 6)), rng.normal(size=(3, 3))
    np.testing.assert_allclose(cof2tc_law(e_y, F, K, BpH, False), e_y @ K.T, rtol=1e-13)
    np.testing.assert_allclose(
        cof2tc_law(e_y, F, K, BpH, True), e_y @ K.T - F @ BpH.T, rtol=1e-12, atol=1e-14
    )


def _raw(**controller):
    raw = loader.read_raw("gui2022-cof2tc")[0]
    raw["controller"].update(controller)
    raw.pop("evaluations", None)  # the scores read the observer: not what is tested here
    return raw


@pytest.mark.parametrize(
    ("drop", "controller", "needles"),
    [
        (
            "estimator",
            {"fault_compensation": True},
            (
                "controller gui2022-cof2tc needs an estimate F_hat",
                "fault_compensation = true",
                'estimator type = "iterative-learning-observer"',
            ),
        ),
        (
            None,
            {"mean_motion": None},
            (
                "controller gui2022-cof2tc needs a reference orbit known on board",
                "controller.mean_motion",
                "[reference]",
            ),
        ),
    ],
)
def test_compositions_without_what_the_law_needs_are_refused(drop, controller, needles):
    raw = _raw(**{k: v for k, v in controller.items() if v is not None})
    if drop:
        del raw[drop]
    for k, v in controller.items():
        if v is None:
            raw["controller"].pop(k, None)
    with pytest.raises(loader.ScenarioError) as err:
        ftc.load_scenario(raw)
    for needle in needles:
        assert needle in str(err.value), (needle, str(err.value))
    # with what it needs, the same composition loads
    ftc.load_scenario(_raw())
