"""``formation-ftc campaign list | run | report`` through the main command line, and the built-in
campaign files."""

from __future__ import annotations

import json
import tomllib

import pytest

from formation_ftc.campaign import builtin_campaigns, make_plan
from formation_ftc.campaign.cli import main as campaign_main
from formation_ftc.cli import main


def test_list_names_first(capsys):
    assert main(["campaign", "list"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    names = [ln.split()[0] for ln in lines]
    assert names == sorted(builtin_campaigns())
    assert {
        "li2020-thm1-vs-sirftc",
        "azizi2009-alpha2-sweep",
        "mehrabian-cases",
        "cw-pd-gains",
    } <= set(names)


def test_run_report_and_errors(tmp_path, tiny, write_campaign, capsys):
    raw = tiny()
    # no traced runs (re-run alone with records: a program of their own); traces: test_runner.py
    raw["traces"]["runs"] = []
    spec = write_campaign(tmp_path / "c.toml", raw)
    out = tmp_path / "out"
    assert (
        main(["campaign", "run", str(spec), "--out", str(out), "--runs", "2", "--no-progress"]) == 0
    )
    err = capsys.readouterr().err
    assert "4 runs (4 ok, 0 failed)" in err
    # --runs changed the campaign: the same directory with the file's runs = 3 is another campaign
    assert main(["campaign", "run", str(spec), "--out", str(out), "--no-progress"]) == 2
    assert "holds another campaign" in capsys.readouterr().err
    # the stand-alone module entry point resumes (nothing to do) with the same options
    assert campaign_main(["run", str(spec), "--out", str(out), "--runs", "2", "--no-progress"]) == 0
    assert "0 chunk(s) computed, 2 kept" in capsys.readouterr().err
    assert main(["campaign", "report", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "4/4 runs done" in printed and "final_position_error_mean" in printed
    assert json.loads((out / "report" / "summary.json").read_text())["runs_done"] == 4
    assert (out / "report" / "sweep_controller.kd.png").exists()

    bad = tiny()
    bad["sample"]["controller.gain"] = {"dist": "uniform", "low": 0.0, "high": 1.0}
    assert (
        main(
            [
                "campaign",
                "run",
                str(write_campaign(tmp_path / "bad.toml", bad)),
                "--out",
                str(tmp_path / "bad"),
            ]
        )
        == 2
    )
    assert "sample.controller.gain: dotted path does not exist" in capsys.readouterr().err
    assert (
        main(
            [
                "campaign",
                "run",
                str(spec),
                "--out",
                str(tmp_path / "x"),
                "--scheduler",
                "tcp://nohost",
            ]
        )
        == 2
    )
    assert "expected tcp://HOST:PORT" in capsys.readouterr().err
    (tmp_path / "foreign").mkdir()
    (tmp_path / "foreign" / "data.csv").write_text("1,2")
    assert main(["campaign", "run", str(spec), "--out", str(tmp_path / "foreign")]) == 2
    assert "refusing to overwrite" in capsys.readouterr().err
    assert main(["campaign", "report", str(tmp_path / "foreign")]) == 2


@pytest.mark.parametrize("name", sorted(builtin_campaigns()))
def test_builtin_campaigns_validate(name):
    """Every built-in campaign is valid against its base scenarios (paths exist, bounds allowed)."""
    meta = tomllib.loads(builtin_campaigns()[name])["campaign"]
    plan = make_plan(name, runs=min(meta["runs"], 5))
    plan.validate_all()
    assert plan.n_runs == plan.n_grid * min(meta["runs"], 5)
