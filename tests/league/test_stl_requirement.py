"""A league requirement in signal temporal logic: validated (the formula, the verdict), recorded in
every run as stl_violation (minus the robustness, computed inside the run), checked against rtamt on a
traced run's recorded signal, and passing runs by its sign when the verdict is "stl"."""

from __future__ import annotations

import tomllib

import numpy as np
import pandas as pd
import pytest
import tomli_w
import xarray as xr

from formation_ftc.league.definition import STL_VIOLATION, LeagueError, load_league
from formation_ftc.league.report import write_leaderboard
from formation_ftc.league.runner import run_league

rtamt = pytest.importorskip("rtamt")
FORMULA = "F[0,20](G(shape_error <= 1))"


def _league(tmp_path, tiny_league, **requirement):
    path = tiny_league(tmp_path, methods=("lqr",), traced=True)
    raw = tomllib.loads(path.read_text())
    raw["league"]["requirement"].update(requirement)
    for k in [k for k, v in requirement.items() if v is None]:
        del raw["league"]["requirement"][k]
    path.write_text(tomli_w.dumps(raw))
    return path


def test_the_definition_adds_the_violation_metric(tmp_path, tiny_league):
    spec = load_league(_league(tmp_path, tiny_league, stl=FORMULA))
    added = [m for m in spec.metrics if m["name"] == STL_VIOLATION]
    assert added == [
        {"name": STL_VIOLATION, "reduce": "stl", "formula": f"not ({FORMULA})", "units": "m"}
    ]
    with pytest.raises(LeagueError, match="position 14"):
        load_league(_league(tmp_path, tiny_league, stl="F[0,20](G(x <=))"))
    with pytest.raises(LeagueError, match="needs league.requirement.stl"):
        load_league(_league(tmp_path, tiny_league, stl=None, verdict="stl"))


def test_a_league_passes_runs_by_the_robustness(tmp_path, tiny_league):
    path = _league(tmp_path, tiny_league, stl=FORMULA, verdict="stl")
    out = tmp_path / "out"
    run_league(path, out, seeds=2)
    board = write_leaderboard(out, plots=False)
    assert board["requirement"]["metric"] == STL_VIOLATION and board["requirement"]["max"] == 0.0
    runs = pd.read_parquet(out / "leaderboard" / "runs.parquet")
    violation = runs[f"metric:{STL_VIOLATION}"].to_numpy(dtype=float)
    assert np.isfinite(violation).all()
    cells = pd.DataFrame(board["cells"])
    for _, c in cells.iterrows():
        sel = runs[(runs.case == c.case) & (runs.level == c.level)]
        passed = (sel.status == "ok") & (sel[f"metric:{STL_VIOLATION}"] <= 0)
        assert c.pass_rate == pytest.approx(passed.mean())
    # a traced run: rtamt on its recorded shape error gives the in-run robustness
    traces = sorted(out.glob("lqr/campaign/traces/*.nc"))
    assert traces
    ds = xr.open_dataset(traces[0])
    run_id = int(traces[0].stem.split("-")[1])
    spec = rtamt.StlDiscreteTimeSpecification()
    spec.declare_var("shape_error", "float")
    step = float(ds["time"].values[1] - ds["time"].values[0])
    spec.set_sampling_period(step, "s", 0.1)
    spec.spec = "eventually[0:20](always(shape_error <= 1))"
    spec.parse()
    t = ds["time"].values - ds["time"].values[0]
    rho = spec.evaluate({"time": list(t), "shape_error": list(ds["shape_error"].values)})[0][1]
    mine = runs[runs.run_id == run_id][f"metric:{STL_VIOLATION}"].iloc[0]
    assert mine == pytest.approx(-rho, abs=1e-12)
