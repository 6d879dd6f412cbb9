"""Shared league fixtures: ``tiny_league(dir, methods=..., **league)`` writes a shortened copy of the
built-in translational league (60 s, scores from 20 s, onset in [30, 40] s, chunks of 4 runs, only the
given methods; every battery case is kept; no step-convergence check unless ``step_check`` is given;
the raw-navigation levels only unless ``filtered``; no traced runs unless ``traced``: the traced runs
are re-run alone with their records, a program of its own to compile for each method)
and returns the path of its file."""

from __future__ import annotations

import shutil
import tomllib
from collections.abc import Callable
from pathlib import Path

import pytest
import tomli_w

from formation_ftc.league.definition import builtin_leagues

DATA = Path(builtin_leagues()["translational"]).parent


def write_tiny_league(
    tmp_path: Path,
    methods=("sir-ftc", "lqr"),
    filtered: bool = False,
    traced: bool = False,
    **league,
) -> Path:
    raw = tomllib.loads((DATA / "league-translational.toml").read_text())
    if not filtered:  # the navigation axis has its own tests (test_navigation_axis.py)
        raw["levels"] = [lv for lv in raw["levels"] if lv.get("navigation", "raw") == "raw"]
    # the step-convergence check has its own test (test_step_check.py): off unless asked for
    league = {"step_check": {"enabled": False}, **league}
    # the traced runs (trajectory plots) have their own tests, the leaderboard's and STL's: off unless asked for
    if not traced:
        league = {"trace_cases": [], **league}
    raw["league"].update(horizon=60.0, settle_start=20.0, chunk_size=4, **league)
    raw["league"]["onset"].update(low=30.0, high=40.0)
    for m in raw["metrics"]:
        if m.get("start") == 300.0:
            m["start"] = 20.0
    raw["methods"] = [m for m in raw["methods"] if m["name"] in methods]
    (tmp_path / "translational").mkdir(exist_ok=True)
    for m in raw["methods"]:
        shutil.copy(DATA / m["scenario"], tmp_path / m["scenario"])
    path = tmp_path / "tiny.toml"
    path.write_text(tomli_w.dumps(raw))
    return path


@pytest.fixture(scope="session")
def tiny_league() -> Callable[..., Path]:
    return write_tiny_league
