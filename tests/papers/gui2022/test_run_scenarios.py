"""gui2022 reproduction: runs of one structure declared as one batch (``batch = "ilo"`` in study.toml)
give what each run alone gives, metric for metric; the truth here is the single-run program, a
separately compiled XLA program (same arithmetic per element, so agreement to 1e-12 relative)."""

from __future__ import annotations

import numpy as np

from formation_ftc.papers._study import _single, load_runs

H = {"simulation.horizon": 2.0}


def test_batch_of_one_structure_equals_the_runs_alone():
    spec = {
        "runs": [
            {"name": "gui2022-ilo", "batch": "ilo"},
            {
                "name": "lmi",
                "scenario": "gui2022-ilo",
                "set": {"estimator.gains": "lmi"},
                "batch": "ilo",
            },
        ]
    }
    batched = load_runs(spec, H)
    assert list(batched) == ["gui2022-ilo", "lmi"]
    for run in batched.values():
        alone = _single(run.scenario)
        assert run.metrics.keys() == alone.metrics.keys() and run.run_s > 0.0
        for k in alone.metrics:
            np.testing.assert_allclose(
                run.metrics[k], alone.metrics[k], rtol=1e-12, atol=1e-300, err_msg=k
            )
        np.testing.assert_allclose(
            run.dataset["fault_estimate"].values,
            alone.dataset["fault_estimate"].values,
            rtol=1e-12,
            atol=1e-15,
        )
    # the two gain sets really differ (the batch did not run one scenario twice)
    m0, m1 = (r.metrics for r in batched.values())
    assert abs(m0["final_fault_err_x"] - m1["final_fault_err_x"]) > 1e-4
