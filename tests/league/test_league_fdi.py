"""Fault detection in the league: a method flying a residual FDI (azizi2009) gets the league's FDI
scores in every cell, and the leaderboard's FDI table (Markdown, HTML, JSON) follows from the runs'
metrics. Truth: hand-made runs with known alarm and fault times; a tiny league's own metrics."""

from __future__ import annotations

import copy
import json
import math
import tomllib

import numpy as np
import pandas as pd
import pytest
import tomli_w

from formation_ftc.exitcodes import jsonable
from formation_ftc.league.definition import load_league
from formation_ftc.league.report import fdi_table, markdown_summary, write_leaderboard
from formation_ftc.league.runner import (
    FDI_METRICS,
    _with_fdi_scores,
    load_league_results,
    plan_cells,
    run_league,
)

HORIZON = 60.0
_DEFINITION = tomli_w.dumps({"league": {"horizon": HORIZON, "requirement": {"metric": "m"}}})


def _runs(rows):
    cols = ["method", "level", "case", "fault_kind", "status", "alarm", "fault", "delay", "iso"]
    df = pd.DataFrame(rows, columns=cols)
    return df.rename(
        columns={
            "alarm": "metric:fdi_alarm_time",
            "fault": "metric:fdi_fault_time",
            "delay": "metric:fdi_detection_delay",
            "iso": "metric:fdi_correct_isolation",
        }
    )


def test_fdi_table_from_hand_made_runs():
    nan = math.nan
    runs = _runs(
        [
            # no fault: one alarm at 30 s (exposure 30 s), one run without alarm (exposure 60 s)
            ("fdi", "u", "none", "none", "ok", 30.0, nan, 0.0, 0.0),
            ("fdi", "u", "none", "none", "ok", nan, nan, 0.0, 0.0),
            # bias: detected 2 s and 4 s after the fault (one isolated right), one missed, one alarm
            # before the fault (not a detection), one diverged run (not counted)
            ("fdi", "u", "bias", "bias", "ok", 32.0, 30.0, 2.0, 1.0),
            ("fdi", "u", "bias", "bias", "ok", 40.0, 36.0, 4.0, 0.0),
            ("fdi", "u", "bias", "bias", "ok", nan, 34.0, 26.0, 0.0),
            ("fdi", "u", "bias", "bias", "ok", 10.0, 30.0, 0.0, 0.0),
            ("fdi", "u", "bias", "bias", "diverged", nan, nan, nan, nan),
            # a method without FDI: its runs have no FDI metric
            ("plain", "u", "none", "none", "ok", nan, nan, nan, nan),
        ]
    )
    out = fdi_table({"definition": _DEFINITION}, runs)
    assert out["methods"] == ["fdi"] and out["without_fdi"] == ["plain"]
    none, bias = out["rows"]
    assert (none["case"], none["runs"], none["false_alarms"], none["missed"]) == ("none", 2, 1, 0)
    assert none["fault_free_hours"] == pytest.approx(90.0 / 3600.0)
    assert none["false_alarms_per_hour"] == pytest.approx(1 / (90.0 / 3600.0))  # = 40 per hour
    assert math.isnan(none["detection_rate"]) and math.isnan(none["mean_detection_delay"])
    assert (bias["runs"], bias["failed"], bias["fault_runs"], bias["detected"]) == (4, 1, 4, 2)
    assert bias["detection_rate"] == 0.5 and bias["mean_detection_delay"] == 3.0
    assert bias["missed"] == 1 and bias["false_alarms"] == 1
    # fault-free exposure: 30 + 36 + 34 + 10 (the early alarm) = 110 s
    assert bias["false_alarms_per_hour"] == pytest.approx(3600.0 / 110.0)
    assert bias["correct_isolation_rate"] == 0.5
    assert isinstance(bias["missed"], int) and isinstance(bias["detection_rate"], float)
    md = markdown_summary(
        {
            "league": "x",
            "version": "1",
            "battery": {"name": "v1", "version": 1},
            "seeds": 2,
            "requirement": {"metric": "m", "max": 1.0, "units": "m"},
            "ranking": {},
            "cells": [],
            "fdi": jsonable(out),  # as the leaderboard stores it
        }
    )
    assert "**FDI**" in md and "No FDI in the loop: plain." in md
    assert "| fdi | u | bias | 4 | 0.5 | 3 | 1 | 1 | 32.7 | 0.5 |" in md
    assert "| fdi | u | none | 2 | - | - | 0 | 1 | 40 | - |" in md


def test_only_methods_with_a_residual_fdi_get_the_fdi_scores(tmp_path, tiny_league):
    path = tiny_league(tmp_path, methods=("azizi2009",))
    cells = plan_cells(load_league(path))
    names = {m["name"] for m in FDI_METRICS}
    for cell in cells["azizi2009"]:
        assert {"type": "fdi-scores"} in cell.raw["evaluations"]
        assert names <= {m["name"] for m in cell.raw["metrics"]}
        assert cell.raw["estimator"]["type"] == "residual-fdi"
        assert cell.raw["supervisor"]["fault_information"] == "estimator"
        assert cell.raw["sensors"]["type"] == "lvlh-relative-state"  # the league's sensors
    # a method without a fault detector (or a cell without the fault battery) is left as it is
    cell = cells["azizi2009"][0].raw
    for drop in ("estimator", "actuator"):
        raw = {k: v for k, v in cell.items() if k != drop}
        evaluations = [e for e in cell["evaluations"] if e["type"] != "fdi-scores"]
        raw.update(evaluations=evaluations, metrics=[])
        assert _with_fdi_scores(copy.deepcopy(raw)) == raw


@pytest.mark.slow
def test_tiny_league_fdi_table_matches_the_runs(tmp_path, tiny_league):
    """azizi2009 alone on a 10 s league (onset in [3, 5] s, unsaturated, 2 seeds): the FDI table of
    the leaderboard (JSON and Markdown) is the runs' own FDI metrics."""
    path = tiny_league(tmp_path, methods=("azizi2009",))
    raw = tomllib.loads(path.read_text())
    raw["league"].update(horizon=10.0, settle_start=3.0)
    raw["league"]["onset"].update(low=3.0, high=5.0)
    raw["levels"] = [lv for lv in raw["levels"] if lv["name"] == "unsaturated"]
    method = (
        tmp_path / "translational" / "azizi2009.toml"
    )  # its [levels.limited] goes with the level
    method.write_text(
        tomli_w.dumps({k: v for k, v in tomllib.loads(method.read_text()).items() if k != "levels"})
    )
    for m in raw["metrics"]:
        if m.get("start") == 20.0:
            m["start"] = 3.0
    path.write_text(tomli_w.dumps(raw))
    out = tmp_path / "out"
    run_league(path, out, seeds=2)
    _, runs = load_league_results(out)
    board = write_leaderboard(out, plots=False)
    saved = json.loads((out / "leaderboard" / "leaderboard.json").read_text())
    assert saved["fdi"]["methods"] == ["azizi2009"] and saved["fdi"]["without_fdi"] == []
    rows = {r["case"]: r for r in saved["fdi"]["rows"]}
    assert set(rows) == set(runs["case"])
    for case, g in runs.groupby("case"):
        r = rows[case]
        alarm = g["metric:fdi_alarm_time"].to_numpy(float)
        fault = g["metric:fdi_fault_time"].to_numpy(float)
        assert r["runs"] == len(g) == 2 and isinstance(r["runs"], int)
        if case == "none":
            assert np.isnan(fault).all() and r["detection_rate"] is None
            assert r["false_alarms"] == int(np.isfinite(alarm).sum())
            exposure = np.where(np.isfinite(alarm), alarm, 10.0).sum() / 3600.0
            assert r["false_alarms_per_hour"] == pytest.approx(r["false_alarms"] / exposure)
            # the evaluation's own false-alarm flag agrees (no fault: any alarm is false)
            assert r["false_alarms"] == int(g["metric:fdi_false_alarm"].sum())
            continue
        if case == "intermittent":
            # on 30 s first: its first off phase is past the 10 s horizon, so the thruster never
            # departs from nominal (no fault in the scores; any alarm is false)
            assert np.isnan(fault).all() and r["fault_runs"] == 0
            assert r["false_alarms"] == int(np.isfinite(alarm).sum())
            continue
        assert np.isfinite(fault).all() and (fault >= 3.0).all() and (fault <= 5.2).all()
        det = np.isfinite(alarm) & (alarm >= fault)
        assert r["detection_rate"] == pytest.approx(det.mean())
        assert r["missed"] == int((~np.isfinite(alarm)).sum())
        assert r["false_alarms"] == int((np.isfinite(alarm) & (alarm < fault)).sum())
        if det.any():
            delay = g["metric:fdi_detection_delay"].to_numpy(float)[det]
            assert r["mean_detection_delay"] == pytest.approx(delay.mean())
            iso = g["metric:fdi_correct_isolation"].to_numpy(float)[det]
            assert r["correct_isolation_rate"] == pytest.approx(iso.mean())
        else:
            assert r["mean_detection_delay"] is None
    assert board["fdi"]["rows"][0]["method"] == "azizi2009"
    md = (out / "leaderboard" / "leaderboard.md").read_text()
    assert "**FDI**" in md and "| azizi2009 | unsaturated | bias | 2 |" in md
    assert "<h2>FDI</h2>" in (out / "leaderboard" / "index.html").read_text()
