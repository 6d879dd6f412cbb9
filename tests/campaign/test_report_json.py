"""``formation-ftc campaign report DIR --json`` (typed summary, metric units, output paths) and a
report whose stdout cannot be written (exit status 1, the report files stay)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import tomli_w

from formation_ftc.cli import main

#: 2 runs of cw-free-drift cut to 10 s (10 steps of 1 s): the cheapest campaign there is
CHEAP = {
    "campaign": {"name": "cheap", "base": "cw-free-drift", "runs": 2, "seed": 1, "chunk_size": 2},
    "overrides": {"simulation.horizon": 10.0},
    "sample": {"plant.mass.0": {"dist": "uniform", "low": 90.0, "high": 110.0}},
}


@pytest.fixture(scope="module")
def campaign_dir(tmp_path_factory) -> Path:
    tmp = tmp_path_factory.mktemp("campaign-json")
    spec = tmp / "cheap.toml"
    spec.write_text(tomli_w.dumps(CHEAP))
    out = tmp / "out"
    assert (
        main(
            [
                "campaign",
                "run",
                str(spec),
                "--out",
                str(out),
                "--workers",
                "1",
                "--no-progress",
                "-q",
            ]
        )
        == 0
    )
    return out


def test_campaign_report_json(campaign_dir, capsys):
    capsys.readouterr()
    assert main(["campaign", "report", str(campaign_dir), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)  # one document, no table in front of it
    summary = doc["summary"]
    assert (
        summary["campaign"] == "cheap" and summary["runs_done"] == 2 and summary["runs_failed"] == 0
    )
    assert summary == json.loads((campaign_dir / "report" / "summary.json").read_text())
    stats = summary["metrics"]["delta_v_total"]
    assert isinstance(stats["n_ok"], int) and isinstance(stats["mean"], float)
    assert doc["units"]["delta_v_total"] == "m s-1" and set(doc["units"]) == set(summary["metrics"])
    assert doc["outputs"]["summary_json"] == str(campaign_dir / "report" / "summary.json")
    assert all(Path(f).is_file() for f in doc["outputs"]["figures"])
    assert main(["campaign", "report", str(campaign_dir / "missing"), "--json"]) == 2
    assert json.loads(capsys.readouterr().out)["exit_code"] == 2


def test_plot_of_a_campaign_directory_draws_its_report_figures(campaign_dir, capsys):
    """``formation-ftc plot DIR`` of a campaign directory: the figures ``campaign report`` draws (the
    same names), here as SVG."""
    capsys.readouterr()
    assert main(["campaign", "report", str(campaign_dir), "--json"]) == 0
    pngs = [Path(f) for f in json.loads(capsys.readouterr().out)["outputs"]["figures"]]
    assert pngs
    assert main(["plot", str(campaign_dir), "--format", "svg", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["kind"] == "campaign" and doc["index"] is None
    assert doc["figures"] == [str(p.with_suffix(".svg")) for p in pngs]
    assert all(p.with_suffix(".svg").read_text().lstrip().startswith("<?xml") for p in pngs)


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
def test_campaign_report_into_a_full_stdout(campaign_dir):
    summary = campaign_dir / "report" / "summary.json"
    summary.unlink(missing_ok=True)
    with open("/dev/full", "w") as full:
        proc = subprocess.run(
            [
                sys.executable,
                "-m",
                "formation_ftc.cli",
                "campaign",
                "report",
                str(campaign_dir),
                "--no-plots",
            ],
            stdout=full,
            stderr=subprocess.PIPE,
            text=True,
            timeout=600,
        )
    assert proc.returncode == 1
    assert (
        proc.stderr.strip().splitlines()[-1]
        == "cannot write to standard output: No space left on device"
    )
    assert "internal error" not in proc.stderr and "Traceback" not in proc.stderr
    assert json.loads(summary.read_text())["runs_done"] == 2  # the report was written all the same
