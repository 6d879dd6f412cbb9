"""``formation-ftc reproduce --json`` with fake reproductions (no simulation): one JSON document on stdout,
tables and progress on stderr, and a total wall time that is the whole wait.

Truths: the fakes' own rows and conditions (counted and read by hand from ``report_fakes``), the files
written, and wall clocks read around the command.
"""

from __future__ import annotations

import json
import time

import pytest
from report_fakes import failing_reproduction, ok_reproduction

from formation_ftc.cli import main
from formation_ftc.report import html as html_report
from formation_ftc.report import reproduce as rp


@pytest.fixture
def fakes(monkeypatch):
    avail = {"alpha": ok_reproduction("alpha"), "broken": failing_reproduction()}
    monkeypatch.setattr(rp, "available_reproductions", lambda: (avail, {}))
    return avail


def test_reproduce_json_document(tmp_path, fakes, capsys, monkeypatch):
    # the index page takes 0.3 s: the reported total must include it (it once stopped before the page)
    write_index = html_report.write_index

    def slow_index(*args, **kwargs):
        time.sleep(0.3)
        return write_index(*args, **kwargs)

    monkeypatch.setattr(html_report, "write_index", slow_index)
    out = tmp_path / "rep"
    t0 = time.perf_counter()
    code = main(["reproduce", "all", "--out", str(out), "--json", "--workers", "1"])
    waited = time.perf_counter() - t0
    captured = capsys.readouterr()
    doc = json.loads(captured.out)  # the whole of stdout is one document
    assert code == 1 and doc["exit_code"] == 1 and doc["failed"] == ["broken"]  # as without --json
    assert "wall time per paper" in captured.err and "report:" in captured.err

    alpha, broken = doc["papers"]["alpha"], doc["papers"]["broken"]
    assert alpha["status"] == "ok" and alpha["error"] is None
    assert broken["status"] == "failed" and broken["error"] == "RuntimeError: solver exploded"
    # report_fakes: settling time matches, peak thrust differs, chattering is not stated
    assert alpha["verdicts"] == {"match": 1, "differs": 1, "not stated": 1}
    assert doc["verdicts"] == alpha["verdicts"]
    settling, thrust, chattering = alpha["rows"]
    assert settling["quantity"] == "settling time" and settling["verdict"] == "match"
    assert settling["published"] == {"text": "10 s (Fig. 3)", "value": 10.0, "units": "s"}
    assert settling["ours"] == {"text": "9.8 s", "value": 9.8, "units": "s"}
    assert settling["criterion"] == "within 5 %"
    assert settling["basis"] == [{"relation": "rel<=", "lhs": 9.8, "rhs": 10.0, "tolerance": 0.05}]
    assert thrust["verdict"] == "differs" and thrust["published"]["value"] is None
    assert thrust["reference"]["value"] == 0.5 and thrust["reference"]["units"] == "N"
    assert chattering["ours"] == {"text": "small", "value": None, "units": None}
    assert chattering["basis"] == []
    names = [c["name"] for c in alpha["conditions"]]
    assert names == ["Laplacian connected", "gain bound", "delay bound"]
    connected, gain, _ = alpha["conditions"]
    assert connected["holds"] is True and connected["value"] == 0.38
    assert connected["bound"] == {"relation": ">", "value": 0.0, "units": None}
    assert gain["holds"] is False and gain["required"] is True
    assert alpha["conditions_summary"]["required_failed"] == 1

    # outputs: what the command wrote
    assert doc["outputs"]["index"] == str(out / "index.html") and (out / "index.html").is_file()
    assert json.loads((out / "summary.json").read_text())["metadata"]["papers"] == [
        "alpha",
        "broken",
    ]
    figures = alpha["outputs"]["figures"]
    assert [f.rsplit("/", 1)[-1] for f in figures] == ["fig3.png", "fig4.png"]
    assert all((out / "alpha" / f.rsplit("/", 1)[-1]).is_file() for f in figures)
    report = json.loads((out / "alpha" / "report.json").read_text())
    assert alpha["wall_time"] == report["wall_time_s"]

    # the total is the wait: the papers, the 0.3 s page and the rest, never more than the call took
    papers = alpha["wall_time"] + broken["wall_time"]
    assert papers + 0.3 <= doc["wall_time"] <= waited
    assert doc["units"] == {"wall_time": "s"}


def test_reproduce_json_errors(tmp_path, fakes, capsys):
    assert main(["reproduce", "nope", "--out", str(tmp_path / "x"), "--json"]) == 2
    captured = capsys.readouterr()
    assert "unknown paper 'nope'" in captured.err
    doc = json.loads(captured.out)
    assert doc["exit_code"] == 2 and doc["error"].startswith("unknown paper 'nope'")
    with pytest.raises(SystemExit) as exc:  # a usage error of the argument parser
        main(["reproduce", "alpha", "--json"])
    assert exc.value.code == 2
    assert json.loads(capsys.readouterr().out) == {
        "error": "formation-ftc reproduce: the following arguments are required: --out",
        "exit_code": 2,
    }
