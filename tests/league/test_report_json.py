"""``formation-ftc league report DIR --json``: the leaderboard with typed values (numpy numbers as JSON
numbers, NaN as null) and the units of the cells' columns. The leaderboard itself is tested end to end
in test_translational_league.py; here ``write_leaderboard`` is replaced by a hand-made one (a league run
costs tens of seconds)."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd

from formation_ftc.cli import main
from formation_ftc.parquet_units import write_parquet


def test_league_report_json(tmp_path, monkeypatch, capsys):
    from formation_ftc.league import report

    cells = pd.DataFrame(
        {
            "method": ["lqr"],
            "level": ["limited"],
            "case": ["bias"],
            "runs": [2],
            "failed": [0],
            "pass_rate": [0.5],
            "rms_shape_error_median": [1.25],
            "settle_time_median": [math.nan],
        }
    )
    board = {
        "league": "tiny",
        "seeds": np.int64(2),
        "quick": np.bool_(False),
        "complete": True,
        "completeness": {
            "complete": True,
            "seeds": 2,
            "seeds_per_cell": {"min": 2, "max": 2},
            "runs": 2,
            "expected_runs": 2,
            "missing_methods": [],
            "cells_unknown": [],
            "incomplete_cells": [],
        },
        "requirement": {"metric": "rms_shape_error", "max": 5.0, "units": "m"},
        "ranking": {
            "limited": [
                {
                    "method": "lqr",
                    "rank": 1,
                    "pass_rate": np.float64(0.5),
                    "rms_shape_error_median": np.float64(1.25),
                    "failed": 0,
                    "runs": 2,
                }
            ]
        },
        "cells": cells.to_dict("records"),
    }

    def fake_write_leaderboard(league_dir, plots=True, tuned=None):
        out = tmp_path / "leaderboard"
        out.mkdir(exist_ok=True)
        write_parquet(
            cells,
            out / "cells.parquet",
            {
                "runs": "1",
                "failed": "1",
                "pass_rate": "1",
                "rms_shape_error_median": "m",
                "settle_time_median": "s",
            },
        )
        return board

    monkeypatch.setattr(report, "write_leaderboard", fake_write_leaderboard)
    assert main(["league", "report", str(tmp_path), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    lb = doc["leaderboard"]
    assert lb["seeds"] == 2 and lb["quick"] is False and lb["requirement"]["max"] == 5.0
    assert lb["ranking"]["limited"][0]["rms_shape_error_median"] == 1.25
    assert lb["cells"][0]["settle_time_median"] is None  # NaN: not finite
    assert doc["units"]["rms_shape_error_median"] == "m" and doc["units"]["pass_rate"] == "1"
    assert doc["outputs"]["leaderboard_json"] == str(tmp_path / "leaderboard" / "leaderboard.json")
    monkeypatch.undo()
    assert main(["league", "report", str(tmp_path / "missing"), "--json"]) == 2
    assert json.loads(capsys.readouterr().out)["exit_code"] == 2


def test_plot_of_a_league_directory_redraws_its_leaderboard(tmp_path, monkeypatch, capsys):
    """``formation-ftc plot DIR`` of a league directory (it holds league.json) writes the leaderboard
    with its figures (the league's report path, replaced here: a league run costs tens of seconds);
    the page embeds PNG, so another format is refused with exit status 2."""
    from formation_ftc.league import report

    calls = []

    def fake_write_leaderboard(league_dir, plots=True, tuned=None):
        calls.append((str(league_dir), plots))
        out = tmp_path / "leaderboard"
        out.mkdir(exist_ok=True)
        (out / "pareto-limited.png").write_bytes(b"\x89PNG")
        return {}

    monkeypatch.setattr(report, "write_leaderboard", fake_write_leaderboard)
    (tmp_path / "league.json").write_text("{}")
    assert main(["plot", str(tmp_path), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert calls == [(str(tmp_path), True)] and doc["kind"] == "league"
    assert doc["figures"] == [str(tmp_path / "leaderboard" / "pareto-limited.png")]
    assert doc["index"] == str(tmp_path / "leaderboard" / "index.html")
    assert main(["plot", str(tmp_path), "--format", "svg"]) == 2
    assert "embeds PNG" in capsys.readouterr().err and len(calls) == 1
