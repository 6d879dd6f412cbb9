"""``tune`` as robust as ``league run``: budgets checked before any work (exit status 2 naming the option
and the range it allows), ``--out`` checked before computing (a file, a campaign or league directory, a
foreign directory, an existing result without ``--force``), a damaged or mistyped ``--step-check-from``
league.json named with its field, the evaluation journal (a killed tuning resumes to the same result,
a journal of another problem is refused) and ``--json``."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

from formation_ftc.campaign.storage import FORMAT, MANIFEST
from formation_ftc.cli import main
from formation_ftc.league import tuning
from formation_ftc.league.tuning import TuneError, TuneJournal, check_tune_budgets
from formation_ftc.limits import Budgets

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def league(tmp_path_factory, tiny_league) -> Path:
    """The tiny league (60 s, 300 steps per run for yang2013) with yang2013 alone."""
    return tiny_league(tmp_path_factory.mktemp("tune-league"), methods=("yang2013",))


def _tune(league: Path, out: Path | str, *extra: str) -> list[str]:
    return [
        "tune",
        "yang2013",
        "--league",
        str(league),
        "--cases",
        "bias",
        "--train-seeds",
        "1",
        "--holdout-seeds",
        "1",
        "--max-evaluations",
        "4",
        "--out",
        str(out),
        *extra,
    ]


def _tree(root: Path) -> list[tuple[str, bytes]]:
    return sorted(
        (p.relative_to(root).as_posix(), p.read_bytes() if p.is_file() else b"")
        for p in root.rglob("*")
    )


# ------------------------------------------------------------------------------------------- budgets
@pytest.mark.parametrize(
    "extra, fragment",
    [
        (["--train-seeds", "1000000000"], "--train-seeds 1,000,000,000: allowed: --train-seeds 1 to 10,000,000"),
        (["--holdout-seeds", "20000000", "--train-start", "30000000"], "--holdout-seeds 20,000,000: allowed: --holdout-seeds 1 to 10,000,000"),
        (["--max-evaluations", "1"], "--max-evaluations 1: allowed: --max-evaluations 2 or more"),
        (["--max-evaluations", "100000", "--max-campaign-steps", "1e6"], "--max-evaluations 100,000: tune yang2013 @ limited would simulate"),
        (["--train-seeds", "5000", "--max-campaign-steps", "1e6"], "--train-seeds 5,000: tune yang2013 @ limited would simulate"),
        (["--max-run-steps", "100"], "tune yang2013 @ limited, cell bias--limited: 300 integration steps"),
        (["--train-seeds", "100", "--max-memory", "1MB"], "--train-seeds 100: tune yang2013 @ limited: a training batch of 100 runs"),
        (["--max-memory", "1kB"], "--train-seeds 1: tune yang2013 @ limited: a training batch of 1 runs needs about"),
        (["--train-start", "0"], "--train-start 0: the training replicates would overlap"),
    ],
    ids=["1e9-train-seeds", "holdout-seeds", "one-evaluation", "evaluations-steps", "train-seeds-steps",
         "steps-per-run", "memory", "memory-one-seed", "train-start"],
)  # fmt: skip
def test_tune_over_budget_exits_2_before_any_work(tmp_path, league, capsys, extra, fragment):
    out = tmp_path / "tuned"
    assert main(_tune(league, out, *extra)) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and fragment in err, err
    assert "Traceback" not in err and "MemoryError" not in err
    assert not out.exists()  # nothing written


@pytest.mark.parametrize("optimiser", ["nelder-mead", "gradient"])
def test_the_allowed_ranges_are_the_budgets_edge(optimiser):
    """Each range a budget error states is tight: its upper end passes the same check, one more fails
    it (budgets: 1e6 run-steps and 1 MB; 3 cells of 300, 300 and 600 steps; one run 2,000 bytes)."""
    cells = [SimpleNamespace(n_steps=n, key=f"c{n}") for n in (300, 300, 600)]
    budgets = Budgets(max_memory=1_000_000, max_run_steps=None, max_campaign_steps=1_000_000)
    base = dict(train_seeds=4, holdout_seeds=16, max_evaluations=60, n_fields=2)
    for option, value in (
        ("max_evaluations", 10**6),
        ("train_seeds", 2000),
        ("holdout_seeds", 10**5),
    ):
        opts = {**base, option: value}
        if option == "holdout_seeds":
            opts["max_evaluations"] = 2
        flag = "--" + option.replace("_", "-")
        kw = dict(optimiser=optimiser, budgets=budgets, where="tune m @ l", run_bytes=2000)
        with pytest.raises(TuneError, match=rf"^{flag} ") as info:
            check_tune_budgets(cells, **opts, **kw)
        allowed = re.search(rf"allowed: {flag} (\d[\d,]*) to ([\d,]+)", str(info.value))
        assert allowed, str(info.value)
        top = int(allowed.group(2).replace(",", ""))
        check_tune_budgets(cells, **{**opts, option: top}, **kw)  # the edge passes
        with pytest.raises(TuneError, match="over the budget"):  # (maybe naming another option)
            check_tune_budgets(cells, **{**opts, option: top + 1}, **kw)


# --------------------------------------------------------------------------------------------- --out
def _campaign_dir(d: Path) -> Path:
    d.mkdir(parents=True)
    (d / MANIFEST).write_text(json.dumps({"format": FORMAT, "spec_hash": "0" * 64}))
    return d


@pytest.mark.parametrize(
    "kind, fragment",
    [
        ("file", "exists and is a file"),
        ("dev-null", "exists and is not a directory"),
        ("under-a-file", "is not a directory; give a directory"),
        ("campaign", "is a campaign directory"),
        ("inside-campaign", "which is a campaign directory"),
        ("league", "is a league directory; give its tuned/ subdirectory"),
        ("foreign", "holds files that are not tuning results (e.g. ['notes.txt'])"),
        ("result", "holds a tuning result of yang2013 at limited already"),
        ("user-file", "holds files that are not tuning results (e.g. ['yang2013--limited.json'])"),
    ],
)
def test_bad_out_exits_2_before_computing(tmp_path, league, capsys, kind, fragment):
    out = tmp_path / "out"
    extra: list[str] = []
    if kind == "file":
        out.write_text("keep me")
    elif kind == "dev-null":
        out = Path("/dev/null")
    elif kind == "under-a-file":
        (tmp_path / "f").write_text("keep me")
        out = tmp_path / "f" / "tuned"
    elif kind == "campaign":
        _campaign_dir(out)
    elif kind == "inside-campaign":
        out = _campaign_dir(tmp_path / "campaign") / "tuned"
    elif kind == "league":
        out.mkdir()
        (out / "league.json").write_text("{}")
    elif kind == "foreign":
        out.mkdir()
        (out / "notes.txt").write_text("mine")
    elif kind == "result":
        out.mkdir()
        (out / "yang2013--limited.json").write_text(json.dumps({"kind": "formation-ftc tuning"}))
    else:  # a user's file of the result's name: never replaced, --force or not
        out.mkdir()
        (out / "yang2013--limited.json").write_text('{"mine": true}')
        extra = ["--force"]
    before = _tree(tmp_path)
    assert main(_tune(league, out, *extra)) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: --out {out}: ") and fragment in err, err
    assert _tree(tmp_path) == before  # nothing written, nothing changed


# ---------------------------------------------------------------------------- --step-check-from
@pytest.mark.parametrize(
    "content, fragment",
    [
        (None, "no {path} (give a league directory"),
        ("not json", "{path} is damaged or unreadable"),
        ("[1, 2]", "{path} is not a league description"),
        ('{"step_check": [1]}', "{path}: field step_check: Input should be a valid dictionary"),
        ('{"step_check": {"yang2013": {"chosen_dt": "0.1"}}}', "{path}: field step_check.yang2013.chosen_dt: Input should be a valid number"),
        ('{"step_check": {"yang2013": {"chosen_dt": -0.1}}}', "{path}: field step_check.yang2013.chosen_dt: Input should be greater than 0"),
        ('{"step_check": {"yang2013": {"converged": true}}}', "{path}: field step_check.yang2013.chosen_dt: Field required"),
    ],
    ids=["missing", "not-json", "list", "step-check-list", "dt-text", "dt-negative", "dt-missing"],
)  # fmt: skip
def test_step_check_from_a_bad_league_json_exits_2(tmp_path, league, capsys, content, fragment):
    run = tmp_path / "run"
    run.mkdir()
    if content is not None:
        (run / "league.json").write_text(content)
    argv = _tune(league, tmp_path / "tuned", "--step-check-from", str(run))
    assert main(argv) == 2
    err = capsys.readouterr().err
    path = run / "league.json"
    assert err.startswith(f"error: --step-check-from {run}: {fragment.format(path=path)}"), err
    assert not (tmp_path / "tuned").exists()


# --------------------------------------------------------------------------------------------- journal
def test_the_journal_refuses_another_problem_and_drops_a_torn_line(tmp_path):
    path = tmp_path / "m--l.journal.jsonl"
    j = TuneJournal(path, {"method": "m", "train_seeds": 3})
    j.put("train 0x1.0p-1", {"metrics": {"x": [1.0, float("nan")]}})
    with path.open("a") as f:
        f.write('{"key": "train 0x1.8p-1", "metri')  # a kill while the line was written
    again = TuneJournal(path, {"method": "m", "train_seeds": 3})
    assert again.resumed == 1 and list(again.entries) == ["train 0x1.0p-1"]
    assert again.get("train 0x1.0p-1")["metrics"]["x"][1] != again.get("train 0x1.0p-1")["metrics"]["x"][1]  # NaN kept  # fmt: skip
    assert (
        path.read_text().endswith("\n") and "metri\n" not in path.read_text()
    )  # dropped on disk too
    with pytest.raises(TuneError, match=r"journal of another tuning problem \(train_seeds: 3 there, 1 here\)"):  # fmt: skip
        TuneJournal(path, {"method": "m", "train_seeds": 1})
    assert TuneJournal(path, {"method": "m", "train_seeds": 3}).resumed == 1  # the refusal kept it
    fresh = TuneJournal(path, {"method": "m", "train_seeds": 1}, force=True)
    assert fresh.resumed == 0 and len(path.read_text().splitlines()) == 1  # discarded: header only
    lines = path.read_text().splitlines()
    path.write_text("\n".join([lines[0], "garbage", json.dumps({"key": "k"})]) + "\n")
    with pytest.raises(TuneError, match=r"line 2 is damaged; .*--force"):
        TuneJournal(path, {"method": "m", "train_seeds": 1})


_SLOW_CHILD = """
import sys, time
from formation_ftc.league import tuning
evaluate = tuning.GainProblem.evaluate
def slow(self, theta):
    out = evaluate(self, theta)
    time.sleep(0.4)  # time for the parent to kill it between two evaluations
    return out
tuning.GainProblem.evaluate = slow
from formation_ftc.cli import main
sys.exit(main(sys.argv[1:]))
"""


def _timeless(result: dict) -> dict:
    out = json.loads(json.dumps(result))
    for key in ("seconds", "provenance"):
        out.pop(key)
    for key in ("seconds", "compile_seconds"):
        out["optimiser"].pop(key)
    return out


@pytest.mark.slow
def test_a_killed_tuning_resumes_to_the_same_result(tmp_path, league, capsys, monkeypatch):
    """``kill -9`` a tuning once some evaluations are journalled (and leave a half-written line), run the
    same command again: it replays the journal instead of computing those evaluations again, and its
    result equals the uninterrupted run's (every number, the optimiser's history included; the wall
    times aside). The uninterrupted run is also the ``--json`` document's check."""
    calls: list[int] = []
    evaluate = tuning.GainProblem.evaluate

    def counted(self, theta):
        calls.append(1)
        return evaluate(self, theta)

    monkeypatch.setattr(tuning.GainProblem, "evaluate", counted)
    argv = [*_tune(league, tmp_path / "whole")[:-2], "--max-evaluations", "6"]
    assert main([*argv, "--out", str(tmp_path / "whole"), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert set(doc) == {"result", "tuning", "wall_time", "units"}
    assert doc["units"] == {"wall_time": "s"} and 0 < doc["wall_time"] < 600
    whole = json.loads(Path(doc["result"]).read_text())
    assert doc["tuning"] == json.loads(json.dumps(whole)) and whole["optimiser"]["evaluations"] >= 4
    n_whole = len(calls)
    assert not list((tmp_path / "whole").glob("*.journal.jsonl"))  # gone once the result is written

    out = tmp_path / "part"
    journal = out / "yang2013--limited.journal.jsonl"
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    child = subprocess.Popen(
        [sys.executable, "-c", _SLOW_CHILD, *argv, "--out", str(out), "-q"],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    try:
        deadline = time.monotonic() + 180
        # header, the paper gains, then two of the optimiser's evaluations
        while not journal.is_file() or len(journal.read_text().splitlines()) < 4:
            assert child.poll() is None, child.stderr.read().decode() if child.stderr else ""
            assert time.monotonic() < deadline, "no evaluation journalled"
            time.sleep(0.05)
        os.kill(child.pid, signal.SIGKILL)
    finally:
        child.kill()
        child.wait()
    assert not (out / "yang2013--limited.json").exists()
    with journal.open("a") as f:
        f.write(
            '{"key": "train 0x1.0p-2", "metrics": {"rms_shape'
        )  # as a kill in the middle of a line
    journalled = len(journal.read_text().splitlines()) - 2  # header and the torn line
    calls.clear()
    assert main([*argv, "--out", str(out)]) == 0
    assert "resuming, " in capsys.readouterr().err
    assert len(calls) == n_whole - journalled  # the journalled evaluations were not computed again
    resumed = json.loads((out / "yang2013--limited.json").read_text())
    assert _timeless(resumed) == _timeless(whole)
    assert not journal.exists()
    # the result is there: a second run refuses to replace it, --force recomputes it
    assert main([*argv, "--out", str(out)]) == 2
    assert "--force replaces it" in capsys.readouterr().err
    assert main([*argv, "--out", str(out), "--force", "-q"]) == 0
    assert _timeless(json.loads((out / "yang2013--limited.json").read_text())) == _timeless(whole)


def test_tune_usage_error_with_json_is_a_json_document(capsys):
    with pytest.raises(SystemExit):
        main(["tune", "yang2013", "--json"])  # no --out
    doc = json.loads(capsys.readouterr().out)
    assert doc["exit_code"] == 2 and "--out" in doc["error"]


def test_a_damaged_journal_of_this_tuning_exits_2_naming_it(tmp_path, league, capsys):
    out = tmp_path / "tuned"
    out.mkdir()
    journal = out / "yang2013--limited.journal.jsonl"
    journal.write_text("not a journal\n")
    assert main(_tune(league, out)) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {journal}: not a tuning journal") and "--force" in err, err
    assert (
        journal.read_text() == "not a journal\n" and not (out / "yang2013--limited.json").exists()
    )
