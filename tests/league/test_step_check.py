"""The league's step-convergence check (formation_ftc.league.step_check): scores compared when the step
halves, the chosen step given to every cell, the record in league.json, reused on a resume."""

from __future__ import annotations

import json
import math

import pytest

from formation_ftc.league import runner
from formation_ftc.league.definition import load_league
from formation_ftc.league.runner import plan_cells, run_league
from formation_ftc.league.step_check import quiet_cell, scores_agree


def test_scores_agree_relative_change_nan_and_rounding():
    assert scores_agree({"a": 100.0, "b": 2.0}, {"a": 101.0, "b": 2.0}, 0.02) == pytest.approx(
        (1.0 / 101.0, "a")
    )
    assert scores_agree({"a": math.nan}, {"a": math.nan}, 0.02) == (0.0, "")  # no sample in either
    assert scores_agree({"a": 1.0}, {"a": math.nan}, 0.02) == (math.inf, "a")
    assert scores_agree({"a": 0.0}, {"a": 1e-12}, 0.02) == (0.0, "")  # zero to rounding
    assert scores_agree({"a": 1.0, "only_a": 5.0}, {"a": 1.0}, 0.02) == (0.0, "")


def test_quiet_cell_switches_noise_off_and_sets_the_onset():
    raw = {
        "sensors": {"type": "x", "position_noise_std": 0.1, "velocity_noise_std": 1e-3},
        "plant": {"process_noise_std": 0.5, "mass": [1.0]},
        "actuator": {"kind": "bias"},
        "simulation": {"dt": 0.1},
    }
    q = quiet_cell(raw, "actuator.onset", 30.0)
    assert q["sensors"]["position_noise_std"] == 0.0 and q["sensors"]["velocity_noise_std"] == 0.0
    assert q["plant"]["process_noise_std"] == 0.0 and q["actuator"]["onset"] == 30.0
    assert raw["sensors"]["position_noise_std"] == 0.1  # the cell itself is untouched


def test_league_chooses_records_and_reuses_each_methods_step(tmp_path, tiny_league, monkeypatch):
    # LQR (a linear law) at its league step: the check must find scores within 2 % when dt halves
    path = tiny_league(tmp_path, methods=("lqr",), step_check={"case": "bias", "max_halvings": 2})
    out = tmp_path / "out"
    run_league(path, out, seeds=1)
    meta = json.loads((out / "league.json").read_text())
    rec = meta["step_check"]["lqr"]
    assert rec["steps"][:2] == [0.2, 0.1] and rec["case"] == "bias"
    assert rec["converged"] and rec["changes"][-1] <= 0.02 and rec["chosen_dt"] in rec["steps"]
    assert set(rec["scores"][0]) >= {"rms_shape_error", "delta_v_total"}
    cell = (out / "lqr" / "cells").glob("*.toml")
    import tomllib

    assert {tomllib.loads(f.read_text())["simulation"]["dt"] for f in cell} == {rec["chosen_dt"]}

    # a resume reuses the recorded check (no check run)
    def no_rerun(*a, **k):
        raise AssertionError("the step check ran again on a resume")

    monkeypatch.setattr("formation_ftc.league.step_check.check_step", no_rerun)
    run_league(path, out, seeds=1)
    assert json.loads((out / "league.json").read_text())["step_check"]["lqr"] == rec


def test_a_check_that_never_agrees_keeps_the_methods_step_and_says_so(tmp_path, tiny_league):
    path = tiny_league(
        tmp_path, methods=("lqr",), step_check={"tolerance": 1e-12, "max_halvings": 0}
    )
    spec = load_league(path)
    cells = plan_cells(spec)
    logs: list[str] = []
    rec = runner._step_checks(spec, cells, None, logs.append)["lqr"]
    assert not rec["converged"] and rec["chosen_dt"] == 0.2 and rec["steps"] == [0.2, 0.1]
    assert len(rec["changes"]) == 1 and rec["changes"][0] > 1e-12
    assert logs[0].startswith("step checks: 1 method(s) (lqr)") and "NOT converged" in logs[1]
    assert {c.raw["simulation"]["dt"] for c in cells["lqr"]} == {0.2}


def test_unknown_check_case_is_named(tmp_path, tiny_league):
    from formation_ftc.league.definition import LeagueError

    path = tiny_league(tmp_path, methods=("lqr",), step_check={"case": "no-such-case"})
    spec = load_league(path)
    with pytest.raises(LeagueError, match="step_check.case"):
        runner._step_checks(spec, plan_cells(spec), None, None)


def test_ignored_scores_such_as_alarm_times_on_the_step_grid_are_left_out(monkeypatch):
    """A detection delay of one step halves with the step by construction: with it ignored the check
    converges on the other scores; with it compared, it never does."""
    import formation_ftc.api as api
    from formation_ftc.league.step_check import check_step

    monkeypatch.setattr(api, "load_scenario", lambda raw: raw)
    monkeypatch.setattr(
        api,
        "simulate_with_metrics",
        lambda cell, raise_on_divergence: (
            None,
            {"rms": 0.5, "fdi_detection_delay": cell["simulation"]["dt"]},
        ),
    )
    raw = {"simulation": {"dt": 0.2}, "actuator": {"onset": 9.0}}
    kw = dict(case="bias", level="u", onset_field="actuator.onset", onset=1.0, max_halvings=1)
    kept = check_step("m", raw, ignore=("fdi_detection_delay",), **kw)
    assert kept.converged and kept.chosen_dt == 0.2 and set(kept.scores[0]) == {"rms"}
    compared = check_step("m", raw, **kw)
    assert not compared.converged and compared.changes == [0.5, 0.5]
