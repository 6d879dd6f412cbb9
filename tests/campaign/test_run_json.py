"""``formation-ftc campaign run --json`` and honest rates: the rate printed (end line, progress bar, JSON
document) is the runs computed over the whole wall time of the command, which once was the speed of
the last chunks only (a 60-run campaign printed "918 runs/s" for about 7 runs/s).

Truths: the chunk files read back with pandas, the runs the campaign diverges by construction (kp =
1e9 N/m blows up RK4 at 0.1 s, as in test_runner), and a wall clock read around the command.
"""

from __future__ import annotations

import json
import re
import time

import pandas as pd
import pytest

from formation_ftc.cli import main


def _run(argv, capsys):
    t0 = time.perf_counter()
    code = main(argv)
    waited = time.perf_counter() - t0
    captured = capsys.readouterr()
    return code, waited, captured


def _rates(text: str) -> list[float]:
    return [float(x) for x in re.findall(r"([0-9.]+(?:e[-+]?\d+)?) runs/s", text)]


def test_campaign_run_json_counts_and_rate(tmp_path, tiny, write_campaign, capsys):
    raw = tiny(runs=2, chunk_size=2)
    raw["sample"]["controller.kp"] = {"grid": [2.0, 1e9]}  # the 1e9 grid point diverges
    raw["sample"]["controller.kd"] = {"dist": "uniform", "low": 20.0, "high": 30.0}
    raw["traces"]["runs"] = [0]
    spec = write_campaign(tmp_path / "c.toml", raw)
    out = tmp_path / "out"
    code, waited, captured = _run(
        ["campaign", "run", str(spec), "--out", str(out), "--json"], capsys
    )
    assert code == 0
    doc = json.loads(captured.out)  # the whole of stdout is one document; progress went to stderr

    stored = pd.concat(pd.read_parquet(p) for p in sorted((out / "chunks").glob("*.parquet")))
    assert doc["campaign"] == "tiny" and doc["dir"] == str(out)
    assert doc["runs"] == {
        "total": 4,
        "done": len(stored),
        "computed": 4,
        "skipped": 0,
        "ok": int((stored["status"] == "ok").sum()),
        "failed": 2,
        "diverged": 2,
    }
    assert doc["runs"]["ok"] == 2
    assert doc["chunks"] == {"total": 2, "computed": 2, "skipped": 0}
    assert doc["outputs"]["traces"] == [str(out / "traces" / "run-000000.nc")]
    assert doc["outputs"]["manifest"] == str(out / "manifest.json")
    assert doc["units"] == {"wall_time": "s", "rate": "s-1"}

    # the rate: runs over the whole wall time of the command, as the clock around it measured
    assert doc["wall_time"] <= waited and doc["wall_time"] >= 0.8 * waited - 0.2
    assert doc["rate"] == pytest.approx(4 / doc["wall_time"])
    printed = _rates(captured.err)  # the progress bar's last value and the end line's
    assert len(printed) >= 2
    for rate in printed:
        assert 4 / waited * 0.9 <= rate <= 4 / (0.8 * waited - 0.2) * 1.1

    # resumed: nothing computed, no rate
    code, _, captured = _run(
        ["campaign", "run", str(spec), "--out", str(out), "--json", "--no-progress"], capsys
    )
    doc = json.loads(captured.out)
    assert code == 0 and doc["rate"] is None
    assert doc["runs"]["computed"] == 0 and doc["runs"]["skipped"] == 4 and doc["runs"]["done"] == 4
    assert doc["chunks"] == {"total": 2, "computed": 0, "skipped": 2}
    assert "runs/s" not in captured.err


def test_campaign_run_json_errors(tmp_path, tiny, write_campaign, capsys):
    spec = write_campaign(tmp_path / "c.toml", tiny())
    with pytest.raises(SystemExit) as exc:  # a usage error of the argument parser
        main(["campaign", "run", str(spec), "--json"])
    assert exc.value.code == 2
    assert json.loads(capsys.readouterr().out) == {
        "error": "formation-ftc campaign run: the following arguments are required: --out",
        "exit_code": 2,
    }
    bad = tiny()
    bad["sample"]["controller.gain"] = {"dist": "uniform", "low": 0.0, "high": 1.0}
    argv = ["campaign", "run", str(write_campaign(tmp_path / "bad.toml", bad))]
    assert main([*argv, "--out", str(tmp_path / "bad"), "--json"]) == 2
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    assert doc["exit_code"] == 2 and "dotted path does not exist" in doc["error"]
    assert "dotted path does not exist" in captured.err
