"""Evaluation ``formation-scores``: the scores against numpy, and the compositions it cannot score
(refused by ``ClosedLoop.validate`` naming the evaluation, what it needs and who provides it)."""

from __future__ import annotations

import numpy as np
import pytest

from formation_ftc.components.evaluations.formation_scores import FormationScores, shape_error
from formation_ftc.config import loader
from formation_ftc.methods.composed import make_loop

SLOTS = [[100.0, 100.0, 0.0], [-100.0, 100.0, 0.0], [-100.0, -100.0, 0.0], [100.0, -100.0, 0.0]]


def test_formation_scores_against_numpy():
    rng = np.random.default_rng(3)
    rho, d = rng.normal(size=(4, 3)) * 100, rng.normal(size=(4, 3)) * 100
    ref = max(
        np.linalg.norm((rho[i] - rho[j]) - (d[i] - d[j])) for i in range(4) for j in range(i + 1, 4)
    )
    assert float(shape_error(rho, d)) == pytest.approx(ref, rel=1e-14)
    assert float(shape_error(rho + 57.0, d)) == pytest.approx(
        ref, rel=1e-12
    )  # blind to a common translation
    f = rng.normal(size=(4, 3))
    m = np.array([100.0, 120.0, 115.0, 108.0])
    out = FormationScores(desired=d, mass=m).outputs({"position": rho, "applied": f})
    np.testing.assert_allclose(out["slot_error"], np.linalg.norm(rho - d, axis=1), rtol=1e-14)
    np.testing.assert_allclose(
        out["applied_acceleration"], np.linalg.norm(f, axis=1) / m, rtol=1e-14
    )


def _with_scores(name: str, **evaluation) -> dict:
    raw, _ = loader.read_raw(name)
    raw["evaluations"] = [{"type": "formation-scores", **evaluation}]
    return raw


def test_the_masses_default_to_the_plants():
    loop = make_loop(loader.validate(_with_scores("cw-pd-fault", desired=SLOTS), "x"))
    np.testing.assert_array_equal(loop.evaluations[0].mass, [100.0, 120.0, 115.0, 108.0])
    given = _with_scores("cw-pd-fault", desired=SLOTS, mass=1.0)
    np.testing.assert_array_equal(make_loop(loader.validate(given, "x")).evaluations[0].mass, 1.0)


@pytest.mark.parametrize(
    ("name", "needle"),
    [
        (  # Gui2022's exact CW plant records its state, no positions
            "gui2022-ilo",
            r"needs the spacecraft positions recorded as the signal position .* to score each "
            r"spacecraft's slot.*provided by: a translational plant",
        ),
        (  # Azizi2009's double integrator is driven by accelerations
            "azizi2009-fault-free",
            r"needs a plant driven by forces \[N\] to score the applied thrust",
        ),
    ],
)
def test_a_plant_it_cannot_score_is_refused(name, needle):
    raw, _ = loader.read_raw(name)
    n = len(raw["plant"]["initial_position"]) if "initial_position" in raw["plant"] else 1
    with pytest.raises(loader.ScenarioError, match=needle):
        loader.validate(_with_scores(name, desired=SLOTS[:n], mass=100.0), name)
