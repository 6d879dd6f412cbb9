"""Running campaigns in-process: batched results equal single runs, chunking does not change the
numbers, diverged runs are recorded as failed, traces and reports are written."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from formation_ftc import api
from formation_ftc.campaign import CampaignStore, make_plan, run_campaign, write_report

# Batched (vmap) and unbatched programs, or vmaps of different widths, are compiled separately by
# XLA and may round differently in the last bit; measured differences are <= 1e-15 relative, so
# 1e-12 is a safe bound that still catches any wrong seed/sample (those change results at O(1e-3+)).
RTOL = 1e-12


def _metrics(df):
    return df[[c for c in df.columns if c.startswith("metric:")]].to_numpy(float)


@pytest.fixture(scope="module")
def base_run(tmp_path_factory):
    """The tiny campaign (2 grid points x 3 runs, chunks of 2) run once in-process."""
    from formation_ftc.campaign.spec import load_campaign  # noqa: F401  (import check)

    raw = {
        "campaign": {
            "name": "tiny",
            "base": "cw-pd-fault",
            "runs": 3,
            "seed": 11,
            "chunk_size": 2,
            "metrics": ["max_position_error", "final_position_error_mean", "delta_v_total"],
        },
        "overrides": {"simulation.horizon": 20.0},
        "sample": {
            "controller.kp": {"dist": "uniform", "low": 1.0, "high": 3.0},
            "controller.kd": {"grid": [10.0, 30.0]},
            "plant.mass.0": {"dist": "normal", "mean": 100.0, "std": 5.0, "low": 80.0},
        },
        "traces": {"runs": [0, 4], "every": 2},
    }
    out = tmp_path_factory.mktemp("campaign") / "tiny"
    return raw, out, run_campaign(raw, out)


def test_batched_runs_equal_single_runs(base_run):
    raw, out, outcome = base_run
    df = outcome.results
    assert outcome.n_runs == 6 and outcome.n_failed == 0 and outcome.chunks_computed == 4
    assert df["run_id"].tolist() == list(range(6)) and (df["status"] == "ok").all()
    plan = make_plan(raw)
    for r in (0, 4, 5):  # one from each of three different chunks
        inp = plan.run_inputs(r)
        assert (
            df.loc[r, "seed"] == inp.seed
            and df.loc[r, "input:controller.kp"] == inp.values["controller.kp"]
        )
        _, single = api.simulate_with_metrics(plan.scenario(inp))  # independent, unbatched path
        for name in raw["campaign"]["metrics"]:
            assert df.loc[r, f"metric:{name}"] == pytest.approx(single[name], rel=RTOL)
    # the runs differ (samples and seeds really reach the simulation)
    assert len(set(df["metric:delta_v_total"].round(9))) == 6


def test_chunking_invariance(base_run, tmp_path):
    raw, _, outcome = base_run
    again = run_campaign(raw, tmp_path / "k3", chunk_size=3)
    a, b = outcome.results, again.results
    cols = [
        "run_id",
        "grid_index",
        "replicate",
        "seed",
        "input:controller.kp",
        "input:controller.kd",
        "input:plant.mass.0",
        "status",
    ]
    pd.testing.assert_frame_equal(a[cols], b[cols])
    np.testing.assert_allclose(_metrics(a), _metrics(b), rtol=RTOL, atol=0)
    assert again.chunks_computed == 2  # 3 runs per grid point fit one chunk each


def test_traces_are_decimated_histories_of_the_selected_runs(base_run):
    raw, out, _ = base_run
    files = sorted(p.name for p in (out / "traces").iterdir())
    assert files == ["run-000000.nc", "run-000004.nc"]
    ds = xr.open_dataset(out / "traces" / "run-000004.nc", engine="h5netcdf")
    # 20 s, record_every 10 steps of 0.1 s -> records every 1 s (21); every 2nd kept -> 11, t = 0, 2, ..., 20
    np.testing.assert_allclose(ds["time"].values, np.arange(0, 21, 2.0))
    assert ds.attrs["run_id"] == 4 and json.loads(ds.attrs["inputs_json"])["controller.kd"] == 30.0
    ds.close()


def test_resume_in_process_skips_finished_chunks(base_run):
    raw, out, outcome = base_run
    chunk_files = sorted((out / "chunks").iterdir())
    stamps = {p.name: p.stat().st_mtime_ns for p in chunk_files}
    chunk_files[-1].unlink()  # lose one chunk
    resumed = run_campaign(raw, out)
    assert resumed.chunks_computed == 1 and resumed.chunks_resumed == 3
    for p in sorted((out / "chunks").iterdir())[:-1]:
        assert p.stat().st_mtime_ns == stamps[p.name]  # untouched
    pd.testing.assert_frame_equal(resumed.results, outcome.results)


def test_diverged_runs_are_recorded_failed_and_the_campaign_continues(tmp_path, tiny):
    raw = tiny(runs=2, chunk_size=2)
    raw["sample"]["controller.kp"] = {"grid": [2.0, 1e9]}  # kp = 1e9 N/m: RK4 at 0.1 s blows up
    raw["sample"]["controller.kd"] = {"dist": "uniform", "low": 20.0, "high": 30.0}
    raw["traces"]["runs"] = [2]
    outcome = run_campaign(raw, tmp_path / "div")
    df = outcome.results
    assert df["status"].tolist() == ["ok", "ok", "failed", "failed"]
    assert outcome.n_failed == 2
    assert df.loc[2, "diagnostic"].startswith("simulation diverged at t = ")
    assert "left its admissible set" in df.loc[2, "diagnostic"] and np.isnan(
        df.loc[2, "metric:delta_v_total"]
    )
    # the replay of the diverging block names the spacecraft and the variable
    assert "spacecraft" in df.loc[2, "diagnostic"] and "<unknown>" not in df.loc[2, "diagnostic"]
    assert np.isfinite(df.loc[0, "metric:delta_v_total"])
    ds = xr.open_dataset(tmp_path / "div" / "traces" / "run-000002.nc", engine="h5netcdf")
    assert (
        ds.attrs["status"] == "failed" and np.isfinite(ds["position"].values).all()
    )  # partial, finite part
    ds.close()
    summary, figures = write_report(tmp_path / "div")
    assert summary["runs_failed"] == 2 and summary["failure_rate"] == 0.5
    by_kp = summary["by_swept_value"]["controller.kp"]
    assert by_kp["2.0"]["failed"] == 0 and by_kp["1000000000.0"]["failed"] == 2
    assert by_kp["1000000000.0"]["metrics"]["delta_v_total"]["failure_rate"] == 1.0


def test_report_statistics_match_numpy(base_run):
    _, out, outcome = base_run
    summary, figures = write_report(out)
    df = outcome.results
    x = df["metric:final_position_error_mean"].to_numpy()
    st = summary["metrics"]["final_position_error_mean"]
    assert st["n_ok"] == 6 and st["failure_rate"] == 0.0
    assert st["mean"] == pytest.approx(x.mean(), rel=1e-14) and st["std"] == pytest.approx(
        x.std(ddof=1), rel=1e-14
    )
    assert st["p5"] == pytest.approx(np.percentile(x, 5), rel=1e-14) and st["max"] == x.max()
    g = summary["by_swept_value"]["controller.kd"]["30.0"]["metrics"]["final_position_error_mean"]
    assert g["mean"] == pytest.approx(x[3:].mean(), rel=1e-14) and g["n_ok"] == 3
    names = sorted(p.name for p in figures)
    assert names == [
        "sensitivity_controller.kp.png",
        "sensitivity_plant.mass.0.png",
        "sweep_controller.kd.png",
    ]
    assert all(p.stat().st_size > 10_000 for p in figures)
    saved = json.loads((out / "report" / "summary.json").read_text())
    assert saved["runs_done"] == 6
    # the report directory is ours: the campaign can still be resumed afterwards
    assert CampaignStore.prepare(out, make_plan(_raw_of(out))).finished() == {0, 1, 2, 3}


def _raw_of(out):
    m = json.loads((out / "manifest.json").read_text())
    return m["spec"]


def test_random_structural_choice_splits_a_chunk_by_static_key(tmp_path, tiny):
    """A random choice of a structural field (controller.mode changes ClosedLoop.static_key) mixes two
    programs in one chunk: each group is its own vmap batch; every run still equals its single run."""
    raw = tiny(runs=4, chunk_size=4, metrics=["delta_v_total"])
    raw["sample"] = {
        "controller.mode": {"choice": ["continuous", "sampled"]},
        "controller.kp": {"dist": "uniform", "low": 1.0, "high": 3.0},
    }
    raw["traces"]["runs"] = []
    plan = make_plan(raw)
    modes = [plan.run_inputs(r).values["controller.mode"] for r in range(4)]
    assert set(modes) == {"continuous", "sampled"}  # this seed gives both in the one chunk
    df = run_campaign(raw, tmp_path / "mixed").results
    assert df["input:controller.mode"].tolist() == modes
    for r in (modes.index("continuous"), modes.index("sampled")):
        _, single = api.simulate_with_metrics(plan.scenario(plan.run_inputs(r)))
        assert df.loc[r, "metric:delta_v_total"] == pytest.approx(single["delta_v_total"], rel=RTOL)


def test_clear_bindings_forgets_the_bound_templates():
    from formation_ftc.campaign import runner

    runner._BINDINGS[("plan", "group")] = None
    runner._VERIFIED.add(("plan", "group"))
    runner.clear_bindings()
    assert ("plan", "group") not in runner._BINDINGS and ("plan", "group") not in runner._VERIFIED
