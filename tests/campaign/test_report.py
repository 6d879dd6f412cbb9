"""Campaign summary statistics (campaign/report.py) on hand-made result tables: numbers against numpy,
failure counting, and metrics that only some base scenarios return."""

from __future__ import annotations

import numpy as np
import pandas as pd

from formation_ftc.campaign.report import summarize


def _table():
    # two bases: "a" returns metrics x and only_a, "b" returns x and only_b; run 2 of "a" failed
    return pd.DataFrame(
        {
            "run_id": [0, 1, 2, 3, 4, 5],
            "scenario": ["a", "a", "a", "b", "b", "b"],
            "status": ["ok", "ok", "failed", "ok", "ok", "ok"],
            "diagnostic": ["", "", "diverged at t = 3 s", "", "", ""],
            "metric:x": [1.0, 2.0, np.nan, 4.0, 5.0, 6.0],
            "metric:only_a": [10.0, 30.0, np.nan, np.nan, np.nan, np.nan],
            "metric:only_b": [np.nan, np.nan, np.nan, 7.0, 8.0, np.inf],
        }
    )


def test_statistics_and_failure_rates():
    s = summarize(_table(), {"campaign": "t", "n_runs": 6, "swept": ["scenario"]})
    x = s["metrics"]["x"]
    assert x["n_ok"] == 5 and abs(x["failure_rate"] - 1 / 6) < 1e-15
    np.testing.assert_allclose(
        [x["mean"], x["std"], x["p50"]], [3.6, np.std([1, 2, 4, 5, 6], ddof=1), 4.0]
    )
    assert s["runs_failed"] == 1 and s["failures"][0]["run_id"] == 2


def test_metric_of_one_base_is_summarised_over_that_base_only():
    s = summarize(_table(), {"campaign": "t", "n_runs": 6, "swept": ["scenario"]})
    only_a = s["metrics"]["only_a"]
    # the three runs of base "a" (one failed), not the three of "b" that do not return it
    assert only_a["n_runs"] == 3 and only_a["n_ok"] == 2 and only_a["mean"] == 20.0
    only_b = s["metrics"]["only_b"]
    assert (
        only_b["n_runs"] == 3
        and only_b["n_ok"] == 2
        and abs(only_b["failure_rate"] - 1 / 3) < 1e-15
    )  # inf
    groups = s["by_swept_value"]["scenario"]
    assert set(groups["a"]["metrics"]) == {"x", "only_a"}
    assert set(groups["b"]["metrics"]) == {"x", "only_b"}
