"""The translational league: definition, validation before any run, a tiny end-to-end run with its
leaderboard, resume, and the rejections of bad league files (exit code 2 from the command line)."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import tomli_w

from formation_ftc.cli import main
from formation_ftc.league.battery import load_battery
from formation_ftc.league.definition import (
    LeagueError,
    builtin_leagues,
    load_league,
    method_scenario,
)
from formation_ftc.league.report import ranking, winners, write_leaderboard
from formation_ftc.league.runner import plan_cells, run_league
from formation_ftc.parquet_units import UNKNOWN, read_units

DATA = Path(builtin_leagues()["translational"]).parent


def test_builtin_league_loads_and_every_cell_validates():
    spec = load_league("translational")
    assert {m.name for m in spec.methods} >= {
        "li2020-thm1",
        "li2020-thm2",
        "sir-ftc",
        "gui2022-lof2tc",
        "gui2022-cof2tc",
        "azizi2009",
        "yang2013",
        "lqr",
    }
    cells = plan_cells(spec)
    battery = load_battery(spec.league.battery)
    raw_levels = [lv for lv in spec.levels if lv.navigation == "raw"]
    actuator_cases = [c for c in battery.cases if not c.communication]
    for cs in cells.values():
        # every actuator case at every raw-navigation level, for every method (the filtered level:
        # test_navigation_axis.py); communication cases only with a network
        assert {(c.case, c.level) for c in cs} >= {
            (c.name, lv.name) for c in actuator_cases for lv in raw_levels
        }
        assert (
            len([c for c in cs if c.level in {lv.name for lv in raw_levels}]) % len(raw_levels) == 0
        )
    assert any(c.case == "link-loss" for c in cells["li2020-thm1"])
    assert not any(c.case == "link-loss" for c in cells["sir-ftc"])
    assert any(c.case == "larger-delays" for c in cells["li2020-thm2"])
    assert not any(c.case == "larger-delays" for c in cells["li2020-thm1"])


def test_every_method_gets_the_same_truth_faults_and_scores():
    spec = load_league("translational")
    battery = load_battery(spec.league.battery)
    case = battery["bias"]
    level = spec.levels[1]
    raws = [
        method_scenario(spec, m, level, case.actuator_fields(saturation=level.saturation))
        for m in spec.methods
    ]
    for raw in raws:
        assert raw["plant"] == raws[0]["plant"]
        assert (
            raw["actuator"]["kind"] == "bias" and raw["actuator"]["saturation"] == level.saturation
        )
        assert raw["actuator"]["bias"] == pytest.approx(0.5 * level.saturation)  # half the limit
        assert raw["metrics"] == raws[0]["metrics"] and raw["evaluations"] == raws[0]["evaluations"]
        assert raw["simulation"]["horizon"] == spec.league.horizon
    # li2020 Thm 1 and Thm 2 share a law, and the -active methods fly the law of their plain method
    assert len({r["controller"]["type"] for r in raws}) == len(raws) - 3


def test_tiny_league_runs_resumes_and_writes_the_leaderboard(tmp_path, tiny_league):
    path = tiny_league(tmp_path, traced=True)
    out = tmp_path / "out"
    outcome = run_league(path, out, seeds=2)
    spec = load_league(path)
    n_cells = sum(len(c) for c in plan_cells(spec).values())
    assert outcome.n_runs == 2 * n_cells
    meta = json.loads((out / "league.json").read_text())
    assert (
        meta["battery"]["name"] == "v1"
        and meta["seeds"] == 2
        and "git_commit" in json.dumps(meta["provenance"])
    )
    board = write_leaderboard(out)
    lb = out / "leaderboard"
    for f in (
        "index.html",
        "leaderboard.json",
        "leaderboard.md",
        "cells.parquet",
        "runs.parquet",
        "ranking.parquet",
        "pareto-limited.png",
        "trajectories.png",
    ):
        assert (lb / f).is_file(), f
    runs = pd.read_parquet(lb / "runs.parquet")
    assert len(runs) == outcome.n_runs and set(runs["method"]) == {"sir-ftc", "lqr"}
    # paired seeds: replicate j has the same drawn onset in every cell and for every method
    onsets = runs.groupby("replicate")["input:actuator.onset"].nunique()
    assert (onsets == 1).all()
    # pass rate recomputed from the runs
    cells = pd.read_parquet(lb / "cells.parquet")
    req = board["requirement"]
    for _, c in cells.iterrows():
        sel = runs[(runs.method == c.method) & (runs.level == c.level) & (runs.case == c.case)]
        passed = (sel.status == "ok") & (sel[f"metric:{req['metric']}"] <= req["max"])
        assert c.pass_rate == pytest.approx(passed.mean())
        ok = sel[sel.status == "ok"][f"metric:{req['metric']}"]
        if len(ok):
            assert c[f"{req['metric']}_median"] == pytest.approx(np.median(ok))
    # units on every numeric column of every Parquet file (league tables and the campaign chunks)
    for table in [
        lb / "cells.parquet",
        lb / "runs.parquet",
        lb / "ranking.parquet",
        *sorted(out.glob("*/campaign/chunks/*.parquet")),
    ]:
        _assert_parquet_units(table)
    cell_units = read_units(lb / "cells.parquet")
    assert cell_units["pass_rate"] == "1" and cell_units["delta_v_total_median"] == "m s-1"
    assert read_units(lb / "runs.parquet")["metric:delta_v_total"] == "m s-1"
    # the ranking's confidence (issue 48) in every format: the 95 % interval of the pass rate, the
    # comparison of the two methods on their paired seeds, the rank shown ("1=" for a tie)
    doc = json.loads((lb / "leaderboard.json").read_text())
    ranked = pd.read_parquet(lb / "ranking.parquet")
    assert read_units(lb / "ranking.parquet")["pass_rate_low"] == "1"
    assert read_units(lb / "ranking.parquet")["rms_shape_error_median_high"] == "m"
    md = (lb / "leaderboard.md").read_text()
    html = (lb / "index.html").read_text()
    for level, rows in doc["ranking"].items():
        top, second = rows
        assert top["pass_rate_low"] <= top["pass_rate"] <= top["pass_rate_high"]
        assert top["rank_display"] in ("1", "1=") and top["test"] is None
        assert second["test"] in ("mcnemar", "wilcoxon") and 0 < second["pairs"] <= top["runs"]
        assert second["rank_display"] == ("2" if second["separated"] else "1=")
        assert second["p_adjusted"] == pytest.approx(second["p_value"])  # one comparison
        shown = (
            f"| {top['rank_display']} | {top['method']} | {top['pass_rate']:.3f} "
            f"[{top['pass_rate_low']:.2f}, {top['pass_rate_high']:.2f}] |"
        )
        assert shown in md, (shown, md)
        mine = ranked[ranked.level == level].set_index("method")
        assert mine.loc[second["method"], "rank_display"] == second["rank_display"]
        assert mine.loc[top["method"], "pass_rate_high"] == pytest.approx(top["pass_rate_high"])
    assert "Intervals: 95 %" in md and "random seed 48" in md and "Holm" in md
    assert "Intervals: 95 %" in html and "pass rate [95 % CI]" in html
    assert doc["ranking_method"].startswith("Intervals: 95 %")
    assert "data:image/png;base64," in html and "Ranking" in html and "sir-ftc" in html
    assert "<script src=" not in html  # self-contained
    # resume: a second run computes nothing and returns the same table
    again = run_league(path, out, seeds=2)
    assert again.n_runs == outcome.n_runs
    runs2 = pd.read_parquet(lb / "runs.parquet")
    assert runs2.equals(runs)
    # a different seed count is another league directory
    with pytest.raises(LeagueError, match="another --out"):
        run_league(path, out, seeds=3)


def _assert_parquet_units(path: Path) -> None:
    """A ``units`` field metadata entry on every numeric column, none on the others, nothing else."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    schema, units = pq.read_schema(path), read_units(path)
    for f in schema:
        numeric = pa.types.is_integer(f.type) or pa.types.is_floating(f.type)
        assert (f.name in units) == numeric and (not numeric or units[f.name]), (path.name, f.name)
        assert units.get(f.name) != UNKNOWN or f.name.startswith("input:"), (path.name, f.name)
    # no PANDAS_ATTRS; the leaderboard's files say whether the league is complete
    allowed = {b"pandas"} | (
        {b"formation_ftc.league.completeness"} if "chunk" not in path.name else set()
    )
    if path.name == "ranking.parquet":  # the sentence on the intervals and tests
        allowed.add(b"formation_ftc.league.ranking_method")
    assert set(schema.metadata or {}) <= allowed, path.name
    assert not json.loads((schema.metadata or {}).get(b"pandas", b"{}")).get("attributes"), (
        path.name
    )


def test_ranking_and_winners_follow_pass_rate_then_median():
    meta = {"definition": (DATA / "league-translational.toml").read_text()}
    cells = pd.DataFrame(
        [
            dict(
                method="a",
                level="L",
                case="none",
                runs=10,
                failed=0,
                pass_rate=1.0,
                rms_shape_error_median=0.5,
                delta_v_total_median=1.0,
            ),
            dict(
                method="b",
                level="L",
                case="none",
                runs=10,
                failed=0,
                pass_rate=1.0,
                rms_shape_error_median=0.2,
                delta_v_total_median=2.0,
            ),
            dict(
                method="c",
                level="L",
                case="none",
                runs=10,
                failed=5,
                pass_rate=0.5,
                rms_shape_error_median=0.1,
                delta_v_total_median=0.5,
            ),
            dict(
                method="a",
                level="L",
                case="bias",
                runs=10,
                failed=0,
                pass_rate=0.9,
                rms_shape_error_median=0.6,
                delta_v_total_median=1.0,
            ),
            dict(
                method="b",
                level="L",
                case="bias",
                runs=10,
                failed=0,
                pass_rate=0.1,
                rms_shape_error_median=3.0,
                delta_v_total_median=2.0,
            ),
            dict(
                method="c",
                level="L",
                case="bias",
                runs=10,
                failed=0,
                pass_rate=0.0,
                rms_shape_error_median=9.0,
                delta_v_total_median=0.5,
            ),
        ]
    )
    rank = ranking(meta, cells)["L"]
    assert [r["method"] for r in rank] == ["a", "b", "c"]  # 0.95, 0.55, 0.25
    assert rank[0]["pass_rate"] == pytest.approx(0.95)
    wins = {w["case"]: w["method"] for w in winners(meta, cells)}
    assert wins == {"none": "b", "bias": "a"}  # tie on pass rate broken by the median


@pytest.mark.parametrize(
    "edit, message",
    [
        (
            lambda r: r["methods"].append(
                {"name": "ghost", "scenario": "translational/ghost.toml"}
            ),
            "ghost.toml",
        ),
        (lambda r: r["league"].update(battery="v99"), "v99"),
        (lambda r: r["league"]["requirement"].update(metric="no_such_metric"), "no_such_metric"),
        (
            lambda r: r["metrics"].append({"name": "bad", "signal": "no_such_signal"}),
            "no_such_signal",
        ),
        (lambda r: r["league"].update(seeds=0), "seeds"),
        (lambda r: r["levels"].append({"name": "limited", "saturation": 1.0}), "duplicate"),
        (
            lambda r: r["league"]["initial_error"].update(seed_field="plant.no_such_seed"),
            "no_such_seed",
        ),
        (
            lambda r: r["league"]["initial_error"].update(field="plant.initial_position"),
            "either seed_field",
        ),
    ],
)
def test_bad_league_files_are_rejected_naming_the_entry(tmp_path, tiny_league, edit, message):
    path = tiny_league(tmp_path)
    raw = tomllib.loads(path.read_text())
    edit(raw)
    path.write_text(tomli_w.dumps(raw))
    with pytest.raises(LeagueError, match=message):
        run_league(path, tmp_path / "out", seeds=1)
    assert not (tmp_path / "out").exists()  # rejected before anything is written


def test_a_method_that_cannot_drive_the_league_plant_is_rejected(tmp_path, tiny_league):
    path = tiny_league(tmp_path)
    bad = tmp_path / "translational" / "attitude-law.toml"
    bad.write_text(
        tomli_w.dumps(
            {"controller": {"type": "networked-el-hinf", "edges": [[1, 2], [2, 3], [3, 4]]}}
        )
    )
    raw = tomllib.loads(path.read_text())
    raw["methods"].append({"name": "attitude-law", "scenario": "translational/attitude-law.toml"})
    path.write_text(tomli_w.dumps(raw))
    with pytest.raises(LeagueError, match="attitude-law cannot run"):
        run_league(path, tmp_path / "out", seeds=1)
    # a method file may not replace the truth or the faults
    bad.write_text(
        tomli_w.dumps({"plant": {"type": "clohessy-wiltshire"}, "controller": {"type": "pd"}})
    )
    with pytest.raises(LeagueError, match="the league owns the truth"):
        plan_cells(load_league(path))


def test_cli_rejects_unknown_method_with_exit_code_2(tmp_path, capsys):
    # in-process (the command line's exit status is main's return value; `python -m formation_ftc`
    # itself is tests/test_cli_conventions.py's)
    argv = ["league", "run", "translational", "--out", str(tmp_path / "o"), "--methods", "nope"]
    assert main([*argv, "--seeds", "1"]) == 2
    err = capsys.readouterr().err
    assert "nope" in err and "li2020-thm1" in err
    assert main(["league", "list"]) == 0
    assert "translational" in capsys.readouterr().out


def test_a_method_states_flight_knowledge_per_level_and_nothing_else(tmp_path, tiny_league):
    """``[levels.<name>]`` of a method file sets its own flight fields at that level only (azizi2009:
    the FDI's thrust rating and what it does at it, at 0.2 N); an unknown level, a truth slot or a slot the file
    does not set is rejected, naming it."""
    path = tiny_league(tmp_path, methods=("azizi2009",))
    cells = plan_cells(load_league(path))["azizi2009"]
    est = {c.level: c.raw["estimator"] for c in cells}
    assert est["limited"]["force_limit"] == 0.2 and est["limited"]["at_limit"] == "clip"
    assert "force_limit" not in est["unsaturated"] and "at_limit" not in est["unsaturated"]
    method = tmp_path / "translational" / "azizi2009.toml"
    base = tomllib.loads(method.read_text())
    for levels, message in [
        ({"tight": {"estimator.force_limit": 0.1}}, "tight: not a level of the league"),
        ({"limited": {"plant.mass": [1.0] * 4}}, "flight slots"),
        ({"limited": {"network.graph": "ring"}}, "flight slots"),
    ]:
        method.write_text(tomli_w.dumps({**base, "levels": levels}))
        with pytest.raises(LeagueError, match=message):
            plan_cells(load_league(path))
    no_estimator = {k: v for k, v in base.items() if k != "estimator"}
    no_estimator["supervisor"] = {**base["supervisor"], "fault_information": "scripted"}
    method.write_text(tomli_w.dumps(no_estimator))
    with pytest.raises(LeagueError, match=r"has no \[estimator\]"):
        plan_cells(load_league(path))


@pytest.mark.parametrize("method", ["gui2022-cof2tc", "gui2022-lof2tc"])
def test_gui2022_league_gain_is_the_printed_one_on_the_league_orbit(method):
    """The gui2022 league files design K by the paper's CARE (34) with its weight 4e-5 on the league
    orbit's CW model instead of quoting the printed K: against the published K (Gui2022, printed to
    4 decimals, for the paper's orbit) the built gain agrees to 1e-4 (the largest difference, 8e-5,
    is the off-diagonal mean-motion term)."""
    from formation_ftc import api

    printed = np.array(
        [
            [0.0063, -0.0002, 0, 0.1127, 0, 0],
            [0.0002, 0.0063, 0, 0, 0.1126, 0],
            [0, 0, 0.0063, 0, 0, 0.1126],
        ]
    )
    cells = plan_cells(load_league("translational"), [method])[method]  # that method's cells alone
    cell = next(c for c in cells if c.case == "none")
    law = api.build_loop(api.load_scenario(cell.raw)).controller.law  # f = m_nom u
    K = np.asarray(law.K)
    assert np.max(np.abs(K - printed)) < 1e-4
