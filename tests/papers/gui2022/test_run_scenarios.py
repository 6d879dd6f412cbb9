"""gui2022 reproduction: scenarios of one structure run as one vmapped batch (run_scenarios) give what
each run alone gives (run_scenario), metric for metric; the truth here is the single-run program, a
separately compiled XLA program (same arithmetic per element, so agreement to 1e-12 relative)."""

from __future__ import annotations

import numpy as np
import pytest

from formation_ftc.api import load_scenario
from formation_ftc.papers.gui2022.reproduction import run_scenario, run_scenarios

H = {"simulation.horizon": 2.0}


def test_batch_of_one_structure_equals_the_runs_alone():
    scns = [
        load_scenario("gui2022-ilo", H),
        load_scenario("gui2022-ilo", {**H, "estimator.gains": "lmi"}),
    ]
    timings: dict = {}
    batched = run_scenarios(scns, timings, ["printed", "lmi"])
    assert set(timings) == {"printed", "lmi"}
    for scn, (ds_b, m_b) in zip(scns, batched, strict=True):
        ds_1, m_1 = run_scenario(scn)
        assert m_b.keys() == m_1.keys()
        for k in m_1:
            np.testing.assert_allclose(m_b[k], m_1[k], rtol=1e-12, atol=1e-300, err_msg=k)
        np.testing.assert_allclose(
            ds_b["fault_estimate"].values, ds_1["fault_estimate"].values, rtol=1e-12, atol=1e-15
        )
    # the two gain sets really differ (the batch did not run one scenario twice)
    assert abs(batched[0][1]["final_fault_err_x"] - batched[1][1]["final_fault_err_x"]) > 1e-4


def test_scenarios_of_different_structures_are_refused():
    with pytest.raises(ValueError, match="static keys differ"):
        run_scenarios([load_scenario("gui2022-ilo", H), load_scenario("gui2022-lof2tc", H)])
