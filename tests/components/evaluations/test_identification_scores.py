"""Evaluation ``identification-scores``: its per-sample scores on hand-made signals (the oracle is the
definition: error on the faulty channel, within 10 %, a healthy channel outside 1 +- 0.1), and its
needs checked when a loop is built."""

from __future__ import annotations

import numpy as np
import pytest

from formation_ftc.components.evaluations.identification_scores import IdentificationScores


def _signals(identified, true, channel, active):
    return {
        "fdi_effectiveness": np.asarray(identified, dtype=float),
        "effectiveness": np.asarray(true, dtype=float),
        "fault_channel": np.asarray(channel, dtype=float),
        "fault_active": np.asarray(float(active)),
    }


NAN = float("nan")
CHANNEL = [[0, 0, 0], [1, 0, 0]]  # spacecraft 2, axis x
TRUE = [[1, 1, 1], [0.5, 1, 1]]


@pytest.mark.parametrize(
    ("identified", "active", "error", "pending", "false"),
    [
        # identified at 0.52 on the faulty channel: error 0.02, within 10 % of 0.5 (0.05)
        ([[1, 1, 1], [0.52, 1, 1]], True, 0.02, 0.0, 0.0),
        # identified at 0.6: error 0.1 > 0.05, still pending
        ([[1, 1, 1], [0.6, 1, 1]], True, 0.1, 1.0, 0.0),
        # not identified yet (NaN): no error, pending
        ([[1, 1, 1], [NAN, 1, 1]], True, NAN, 1.0, 0.0),
        # a healthy channel identified at 0.85: a false identification
        ([[0.85, 1, 1], [0.5, 1, 1]], True, 0.0, 0.0, 1.0),
        # an outage (true 0) identified at 0.005: within the absolute 0.01
        ([[1, 1, 1], [0.005, 1, 1]], True, 0.005, 0.0, 0.0),
        # before the onset: nothing pending, no error; a channel at 0.5 is a false identification
        ([[1, 1, 1], [0.5, 1, 1]], False, NAN, 0.0, 1.0),
    ],
)
def test_scores_of_hand_made_samples(identified, active, error, pending, false):
    true = [[1, 1, 1], [0.0, 1, 1]] if identified[1][0] == 0.005 else TRUE
    out = IdentificationScores().outputs(_signals(identified, true, CHANNEL, active))
    np.testing.assert_allclose(float(out["id_effectiveness_error"]), error, atol=1e-12)
    assert float(out["id_pending"]) == pending
    assert float(out["id_false"]) == false


def test_needs_a_fault_identification(tmp_path):
    """On a loop whose FDI does not identify, the evaluation is refused, naming what it needs."""
    from formation_ftc.api import load_scenario
    from formation_ftc.config.loader import ScenarioError

    with pytest.raises(ScenarioError, match="fault-identification|identif"):
        load_scenario("cw-fdi-thruster-bias", {"evaluations": [{"type": "identification-scores"}]})
