"""``league run`` as robust as ``campaign run``: budgets on the seed count and bad ``--out`` paths end with
exit status 2 before anything is written, ``league.json`` is written atomically, an interrupted league
resumes to the same numbers, method worker processes die with a killed league, ``--workers`` is capped
with a warning, and a failing stderr never costs a result."""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from formation_ftc.campaign import executors
from formation_ftc.campaign.storage import FORMAT, MANIFEST, CampaignStore
from formation_ftc.cli import main
from formation_ftc.league import runner
from formation_ftc.league.runner import LEAGUE_FILE, load_league_results, run_league


def _run(league: Path, out: Path | str, *extra: str) -> list[str]:
    return [
        "league",
        "run",
        str(league),
        "--out",
        str(out),
        "--methods",
        "lqr",
        "--no-plots",
        "--workers",
        "1",
        *extra,
    ]


@pytest.fixture(scope="module")
def reference(tmp_path_factory, tiny_league):
    """The tiny league with lqr alone, 2 seeds, run once without interruption: (league file, directory,
    results sorted by run)."""
    root = tmp_path_factory.mktemp("league-reference")
    path = tiny_league(root, methods=("lqr",))
    run_league(path, root / "out", seeds=2)
    return path, root / "out", _sorted(load_league_results(root / "out")[1])


def _sorted(runs: pd.DataFrame) -> pd.DataFrame:
    cols = ["method", "run_id", "status"] + sorted(
        c for c in runs.columns if c.startswith(("metric:", "input:"))
    )
    return runs[cols].sort_values(["method", "run_id"]).reset_index(drop=True)


# ------------------------------------------------------------------------------------------- budgets
@pytest.mark.parametrize(
    "extra, fragment",
    [
        (["--seeds", "1000000000"], "allowed: --seeds 1 to 10,000,000"),
        (["--seeds", "10000001"], "allowed: --seeds 1 to 10,000,000"),
        (["--seeds", "1000", "--max-campaign-steps", "1e6"], "allowed: --seeds 1 to 238 "),
        (["--seeds", "1", "--max-campaign-steps", "1000"], "even 1 seed per cell"),
        (["--seeds", "2", "--max-run-steps", "100"], "--max-run-steps"),
        (["--seeds", "2", "--max-memory", "1kB"], "lower league.chunk_size"),
    ],
    ids=[
        "1e9-seeds",
        "over-max-runs",
        "run-steps-budget",
        "budget-below-one-seed",
        "steps-per-run",
        "memory",
    ],
)
def test_league_over_budget_exits_2_before_writing(tmp_path, tiny_league, capsys, extra, fragment):
    league = tiny_league(
        tmp_path, methods=("lqr",)
    )  # 14 cells of 300 steps: 4,200 run-steps per seed
    out = tmp_path / "out"
    assert main(_run(league, out, *extra)) == 2
    err = capsys.readouterr().err
    assert fragment in err and "Traceback" not in err, err
    if "allowed" in fragment:
        assert err.startswith(f"error: --seeds {int(extra[1]):,}: league ")
    assert not out.exists()  # nothing written


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
        ("non-json", "league.json is damaged or unreadable"),
        ("truncated", "league.json is damaged or unreadable"),
        ("not-a-league", "league.json is not a league description"),
        ("campaign", "is a campaign directory"),
        ("inside-campaign", "which is a campaign directory"),
        ("foreign", "is not empty and holds no league.json"),
    ],
)
def test_bad_out_exits_2_naming_out(tmp_path, tiny_league, capsys, kind, fragment):
    league = tiny_league(tmp_path, methods=("lqr",))
    out = tmp_path / "out"
    if kind == "file":
        out.write_text("keep me")
    elif kind == "dev-null":
        out = Path("/dev/null")
    elif kind in ("non-json", "truncated", "not-a-league"):
        out.mkdir()
        text = {
            "non-json": "not json at all",
            "truncated": '{"name": "translational-tiny", "hash": "ab',
            "not-a-league": '["a", "list"]',
        }[kind]
        (out / LEAGUE_FILE).write_text(text)
    elif kind == "campaign":
        _campaign_dir(out)
    elif kind == "inside-campaign":
        out = _campaign_dir(tmp_path / "campaign") / "league"
    else:
        out.mkdir()
        (out / "notes.txt").write_text("mine")
    before = sorted(
        (p.relative_to(tmp_path).as_posix(), p.read_bytes() if p.is_file() else b"")
        for p in tmp_path.rglob("*")
    )
    assert main(_run(league, out, "--seeds", "1")) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: --out {out}: ") and fragment in err and "Traceback" not in err, (
        err
    )
    after = sorted(
        (p.relative_to(tmp_path).as_posix(), p.read_bytes() if p.is_file() else b"")
        for p in tmp_path.rglob("*")
    )
    assert after == before  # nothing written, nothing changed


# ----------------------------------------------------------------------------------- atomic inputs
def _stop_before_running(*args, **kwargs):
    raise KeyboardInterrupt  # stands for a kill once the league's inputs are written


def test_league_json_and_cells_are_written_atomically(tmp_path, tiny_league, monkeypatch):
    league = tiny_league(tmp_path, methods=("lqr",))
    out = tmp_path / "out"
    monkeypatch.setattr(runner, "_check_batch_memory", lambda *args: None)
    monkeypatch.setattr("formation_ftc.campaign.runner.run_campaign", _stop_before_running)
    with pytest.raises(KeyboardInterrupt):
        run_league(league, out, seeds=1)
    old = (out / LEAGUE_FILE).read_text()
    assert json.loads(old)["seeds"] == 1 and len(list((out / "lqr" / "cells").glob("*.toml"))) == 14
    cell = sorted((out / "lqr" / "cells").glob("*.toml"))[0]
    cell.write_text("# edited: rewritten by the next run")
    fsync = os.fsync
    calls: list[int] = []

    def fsync_failing_at(n: int):
        def fail(fd: int) -> None:
            calls.append(fd)
            if len(calls) >= n:
                raise OSError(
                    28, "No space left on device"
                )  # data written, not yet renamed into place
            fsync(fd)

        return fail

    monkeypatch.setattr(os, "fsync", fsync_failing_at(1))  # league.json fails
    with pytest.raises(OSError, match="No space left on device") as full:  # exit status 3
        run_league(league, out, seeds=1)
    assert full.value.filename == str(out)
    assert (out / LEAGUE_FILE).read_text() == old  # the previous league.json, whole
    calls.clear()
    monkeypatch.setattr(
        os, "fsync", fsync_failing_at(2)
    )  # league.json written, then the edited cell fails
    with pytest.raises(OSError, match="No space left on device"):
        run_league(league, out, seeds=1)
    assert json.loads((out / LEAGUE_FILE).read_text())["hash"] == json.loads(old)["hash"]
    assert cell.read_text() == "# edited: rewritten by the next run"  # the previous content, whole
    assert not [p for p in out.rglob(".*") if ".tmp-" in p.name]  # no temporary file left behind


# --------------------------------------------------------------------------------------------- resume
def test_an_interrupted_league_resumes_to_the_same_numbers(tmp_path, reference, monkeypatch):
    league, _, expected = reference
    out = tmp_path / "out"
    write_chunk = CampaignStore.write_chunk
    written: list[int] = []

    def interrupted(self, chunk_id, table, traces=None):
        if len(written) == 5:
            raise KeyboardInterrupt  # as a kill after 5 of the 14 chunks
        written.append(chunk_id)
        return write_chunk(self, chunk_id, table, traces)

    monkeypatch.setattr(CampaignStore, "write_chunk", interrupted)
    with pytest.raises(KeyboardInterrupt):
        run_league(league, out, seeds=2)
    monkeypatch.undo()
    chunks = out / "lqr" / "campaign" / "chunks"
    kept = {p.name: p.stat().st_mtime_ns for p in chunks.glob("chunk-*.parquet")}
    assert len(kept) == 5

    def broken_stderr(line: str) -> None:
        raise OSError(28, "No space left on device")  # 2>/dev/full

    outcome = run_league(league, out, seeds=2, log=broken_stderr, progress=True)
    assert outcome.n_runs == 28
    assert {
        p.name: p.stat().st_mtime_ns for p in chunks.glob("chunk-*.parquet") if p.name in kept
    } == kept
    pd.testing.assert_frame_equal(_sorted(load_league_results(out)[1]), expected)


def test_a_resume_with_other_methods_keeps_the_earlier_ones_listed(
    tmp_path, tiny_league, monkeypatch
):
    league = tiny_league(tmp_path)  # sir-ftc and lqr
    out = tmp_path / "out"
    monkeypatch.setattr(runner, "_check_batch_memory", lambda *args: None)
    monkeypatch.setattr("formation_ftc.campaign.runner.run_campaign", _stop_before_running)
    for method in ("sir-ftc", "lqr"):
        with pytest.raises(KeyboardInterrupt):
            run_league(league, out, seeds=1, methods=[method])
    assert [m["name"] for m in json.loads((out / LEAGUE_FILE).read_text())["methods"]] == [
        "sir-ftc",
        "lqr",
    ]


# -------------------------------------------------------------------------------------------- workers
def _children(pid: int) -> set[int]:
    out = set()
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = Path(f"/proc/{entry}/stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                out.add(int(entry))
    return out


def _loaded_jax(pid: int) -> bool:
    try:
        return "jaxlib" in Path(f"/proc/{pid}/maps").read_text()
    except OSError:
        return False


def _alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")
def test_method_workers_die_with_a_killed_league(tmp_path, tiny_league):
    if executors.cap_workers(2, per_worker_bytes=runner.METHOD_WORKER_BYTES, what="test") < 2:
        pytest.skip("fewer than 2 cores or too little memory for 2 method processes")
    league = tiny_league(tmp_path)  # sir-ftc and lqr
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "formation_ftc",
            "league",
            "run",
            str(league),
            "--out",
            str(out),
            "--seeds",
            "1",
            "--workers",
            "2",
            "--no-progress",
            "--no-plots",
            "--max-memory",
            "0",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    children: set[int] = set()
    try:
        deadline = time.monotonic() + 90
        # both method workers have imported JAX (the pool's initializer and then the method's campaign
        # come right after): without the initializer they would compute on for the whole campaign
        while len([c for c in _children(proc.pid) if _loaded_jax(c)]) < 2:
            assert proc.poll() is None, proc.stderr.read().decode() if proc.stderr else ""
            assert time.monotonic() < deadline, "the method workers did not start"
            time.sleep(0.2)
        time.sleep(1.0)
        children = _children(proc.pid)
        assert len(children) >= 2
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        deadline = time.monotonic() + 10
        while any(_alive(c) for c in children) and time.monotonic() < deadline:
            time.sleep(0.2)
        assert not [c for c in children if _alive(c)], (
            "worker processes outlived their killed league"
        )
    finally:
        proc.kill()
        proc.wait()
        for c in children:
            if _alive(c):
                os.kill(c, signal.SIGKILL)


def test_cap_workers_warns_when_it_lowers_the_count(monkeypatch, capsys):
    monkeypatch.setattr(executors, "schedulable_cpus", lambda: 4)
    monkeypatch.setattr(executors, "available_memory", lambda: 3_000_000_000)
    assert executors.cap_workers(2, per_worker_bytes=1_200_000_000, what="--workers") == 2
    assert capsys.readouterr().err == ""
    assert executors.cap_workers(8, per_worker_bytes=1_200_000_000, what="--workers") == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(
        "warning: --workers: 8 worker processes asked for, using 2 (4 "
    )
    assert "2.79 GiB of memory available" in err
    monkeypatch.setattr(
        executors, "available_memory", lambda: None
    )  # unknown: capped by the cores only
    assert executors.cap_workers(8, per_worker_bytes=1_200_000_000, what="--workers") == 4
    monkeypatch.setattr(executors, "available_memory", lambda: 10)
    assert (
        executors.cap_workers(3, per_worker_bytes=1_200_000_000, what="--workers") == 1
    )  # at least one
    monkeypatch.setattr(sys, "stderr", open(os.devnull, "w"))  # noqa: SIM115
    sys.stderr.close()
    assert (
        executors.cap_workers(3, per_worker_bytes=1_200_000_000, what="--workers") == 1
    )  # closed stderr


# ------------------------------------------------------------------------------------ progress, stderr
def test_method_progress_lines_follow_the_stored_chunks(tmp_path):
    from rich.console import Console

    chunks = {m: tmp_path / m / "chunks" for m in ("lqr", "sir-ftc")}
    for d in chunks.values():
        d.mkdir(parents=True)
    # 5 seeds in chunks of 2 per cell: chunks 0, 1, 2 (2, 2, 1 runs) are cell 0, chunk 3 starts cell 1
    for cid in (0, 2, 3):
        (chunks["lqr"] / f"chunk-{cid:06d}.parquet").write_bytes(b"")
    (chunks["lqr"] / ".chunk-000001.parquet.tmp-77").write_bytes(b"")  # in progress: not counted
    assert runner._stored_runs(chunks["lqr"], 5, 2) == 5
    assert runner._stored_runs(tmp_path / "absent", 5, 2) == 0
    buf = io.StringIO()
    console = Console(file=buf, force_terminal=True, width=120)
    watched = [(m, d, 10) for m, d in chunks.items()]
    with runner._MethodProgress(watched, 5, 2, console=console, interval=0.05):
        (chunks["sir-ftc"] / "chunk-000001.parquet").write_bytes(b"")
        time.sleep(0.3)
    text = buf.getvalue()
    assert "lqr" in text and "5/10" in text and "sir-ftc" in text and "2/10" in text

    class Full(io.StringIO):
        def write(self, s):
            raise OSError(28, "No space left on device")

    for enabled in (True, False):  # a full stderr or --no-progress: no bar, no error
        with runner._MethodProgress(
            watched,
            5,
            2,
            enabled=enabled,
            console=Console(file=Full(), force_terminal=True),
            interval=0.01,
        ):
            time.sleep(0.05)
    not_a_tty = io.StringIO()
    with runner._MethodProgress(watched, 5, 2, console=Console(file=not_a_tty), interval=0.01):
        time.sleep(0.05)
    assert not_a_tty.getvalue() == ""


def test_league_log_lines_survive_a_closed_or_full_stderr(monkeypatch):
    closed = io.StringIO()
    closed.close()
    full = open("/dev/full", "w")  # noqa: SIM115 - closed below, where its unwritten line fails again
    from formation_ftc.exitcodes import lossy_stderr

    for stream in (full, closed):
        monkeypatch.setattr(sys, "stderr", stream)
        with (
            lossy_stderr()
        ):  # what formation-ftc's main wraps every command in, league run included
            print("lqr: 28 runs, 0 failed, 3.0 s", file=sys.stderr, flush=True)  # no exception
    monkeypatch.undo()
    with pytest.raises(OSError):
        full.close()


def test_step_checks_show_progress_from_the_first_second(tmp_path, tiny_league, monkeypatch):
    """The step checks run before any campaign: their progress line (integration steps, elapsed, ETA)
    is on the terminal while the first check simulation still runs, and its total grows when a
    method's step is halved beyond dt/2 (fake simulations: dt, dt/2, dt/4 of the check cell)."""
    from formation_ftc.league import step_check
    from formation_ftc.league.definition import load_league

    spec = load_league(tiny_league(tmp_path, methods=("lqr",), step_check={"enabled": True}))
    cells = runner.plan_cells(spec, ["lqr"])
    n0 = next(c for c in cells["lqr"] if c.key == "bias--unsaturated").n_steps

    class Tty(io.StringIO):
        def isatty(self) -> bool:
            return True

    tty = Tty()
    monkeypatch.setattr(sys, "stderr", tty)
    during: list[str] = []

    def fake_check(name, raw, *, on_simulation, case, level, **_):
        dt = float(raw["simulation"]["dt"])
        for d in (dt, dt / 2, dt / 4):
            on_simulation(d, False)
            time.sleep(0.6)  # a simulation running
            during.append(tty.getvalue())
            on_simulation(d, True)
        return step_check.StepCheckResult(
            name, case, level, 0.02, [dt, dt / 2, dt / 4], [{}, {}, {}], [0.1, 0.01], ["x", "x"],
            converged=True, chosen_dt=dt / 2,
        )  # fmt: skip

    monkeypatch.setattr(step_check, "check_step", fake_check)
    lines: list[str] = []
    records = runner._step_checks(spec, cells, None, lines.append, progress=True)
    assert lines[0].startswith("step checks: 1 method(s) (lqr)")
    assert "step checks" in during[0] and f"0/{3 * n0}" in during[0]  # before any simulation ended
    assert f"{7 * n0}/{7 * n0}" in tty.getvalue()  # n0 + 2 n0 planned, 4 n0 added by the halving
    assert records["lqr"]["chosen_dt"] == pytest.approx(60.0 / (2 * n0))
    assert {c.n_steps for c in cells["lqr"]} == {2 * n0}


# ------------------------------------------------------------------------ league report: types, gaps
@pytest.mark.parametrize(
    "edit, field",
    [
        (lambda m: m.update(seeds="2"), "field seeds: Input should be a valid integer (got '2')"),
        (lambda m: m["battery"]["cases"][0].update(kind=1), "field battery.cases.0.kind: Input should be a valid string"),
        (lambda m: m["methods"][0].update(name="../lqr"), "field methods.0.name: Value error, '../lqr' is not a name"),
        (lambda m: m.update(quick="no"), "field quick: Input should be a valid boolean"),
        (lambda m: m.update(levels={"name": "limited"}), "field levels: Input should be a valid list"),
        (lambda m: m.update(step_check={"lqr": {"chosen_dt": 0}}), "field step_check.lqr.chosen_dt: Input should be greater than 0"),
        (lambda m: m.update(definition="[league"), "field definition: not a league definition"),
    ],
    ids=["seeds-text", "case-kind", "method-path", "quick-text", "levels-object", "step-zero", "definition"],
)  # fmt: skip
def test_league_report_of_a_mistyped_league_json_exits_2(tmp_path, reference, capsys, edit, field):
    _, ref_dir, _ = reference
    d = tmp_path / "league"
    d.mkdir()
    meta = json.loads((ref_dir / LEAGUE_FILE).read_text())
    edit(meta)
    (d / LEAGUE_FILE).write_text(json.dumps(meta))
    assert main(["league", "report", str(d), "--no-plots", "--json"]) == 2
    captured = capsys.readouterr()
    assert captured.err.startswith(f"error: {d}: {d / LEAGUE_FILE}: {field}"), captured.err
    assert json.loads(captured.out)["exit_code"] == 2
    assert not (d / "leaderboard").exists()


def _league_copy(reference, tmp_path: Path) -> Path:
    import shutil

    d = tmp_path / "league"
    shutil.copytree(reference[1], d)
    shutil.rmtree(d / "leaderboard", ignore_errors=True)
    return d


def _file_completeness(path: Path) -> dict:
    import pyarrow.parquet as pq

    return json.loads(pq.read_schema(path).metadata[b"formation_ftc.league.completeness"])


def test_a_complete_league_report_says_its_seeds(tmp_path, reference, capsys):
    d = _league_copy(reference, tmp_path)
    assert main(["league", "report", str(d), "--no-plots", "--json"]) == 0
    board = json.loads(capsys.readouterr().out)["leaderboard"]
    comp = board["completeness"]
    assert board["complete"] is comp["complete"] is True
    assert (
        comp["seeds_per_cell"] == {"min": 2, "max": 2}
        and comp["runs"] == comp["expected_runs"] == 28
    )
    md = (d / "leaderboard" / "leaderboard.md").read_text()
    page = (d / "leaderboard" / "index.html").read_text()
    assert "2 seeds per cell;" in md and "2 seeds per cell." in page
    assert "INCOMPLETE" not in md + page
    # one method: rank 1 with its 95 % interval over the 2 seeds, no comparison
    for rows in board["ranking"].values():
        (r,) = rows
        assert r["rank_display"] == "1" and r["tied"] is False and r["seeds"] == 2
        assert r["pass_rate_low"] <= r["pass_rate"] <= r["pass_rate_high"]
        assert (
            f"| 1 | lqr | {r['pass_rate']:.3f} [{r['pass_rate_low']:.2f}, "
            f"{r['pass_rate_high']:.2f}] |" in md
        )
    for name in ("cells.parquet", "runs.parquet", "ranking.parquet"):
        assert _file_completeness(d / "leaderboard" / name) == comp


def test_an_incomplete_league_is_reported_as_such_in_every_format(tmp_path, reference, capsys):
    """A chunk missing (one cell's 2 runs) and a listed method without a directory: every format says
    the league is incomplete, names the cell and the method, and gives the seeds found per cell
    (0-2) next to the configured 2."""
    import pyarrow.parquet as pq

    d = _league_copy(reference, tmp_path)
    chunk = sorted((d / "lqr" / "campaign" / "chunks").glob("chunk-*.parquet"))[5]
    keys = {Path(str(s)).stem for s in pq.read_table(chunk).to_pandas()["scenario"]}
    assert len(keys) == 1  # a chunk never spans two cells
    case, level = keys.pop().split("--")
    chunk.unlink()
    meta = json.loads((d / LEAGUE_FILE).read_text())
    meta["methods"].append({"name": "sir-ftc"})  # listed, its directory gone
    (d / LEAGUE_FILE).write_text(json.dumps(meta))

    assert main(["league", "report", str(d), "--no-plots"]) == 0
    text = capsys.readouterr().out
    assert text.startswith("INCOMPLETE league: 26 of 28 planned runs found")
    assert "methods without results: sir-ftc" in text
    assert f"lqr {case}/{level} (0 of 2 runs)" in text
    assert "0-2 seeds per cell (2 configured)" in text

    assert main(["league", "report", str(d), "--no-plots", "--json"]) == 0
    captured = capsys.readouterr()
    assert captured.err.startswith("warning: INCOMPLETE league")
    board = json.loads(captured.out)["leaderboard"]
    comp = board["completeness"]
    assert board["complete"] is False and comp["complete"] is False
    assert comp["missing_methods"] == comp["cells_unknown"] == ["sir-ftc"]
    assert comp["incomplete_cells"] == [
        {"method": "lqr", "case": case, "level": level, "runs": 0, "expected": 2}
    ]
    assert comp["seeds_per_cell"] == {"min": 0, "max": 2}
    runs = pd.read_parquet(d / "leaderboard" / "runs.parquet")
    assert comp["runs"] == len(runs) == 26 and comp["expected_runs"] == 28
    assert (case, level) not in {(c["case"], c["level"]) for c in board["cells"]}
    assert json.loads((d / "leaderboard" / "leaderboard.json").read_text())["completeness"] == comp
    md = (d / "leaderboard" / "leaderboard.md").read_text()
    page = (d / "leaderboard" / "index.html").read_text()
    for doc in (md, page):
        assert "INCOMPLETE league" in doc and "sir-ftc" in doc and f"{case}/{level}" in doc
        assert "0-2 seeds per cell (2 configured)" in doc
    assert md.startswith("**INCOMPLETE league")
    for name in ("cells.parquet", "runs.parquet", "ranking.parquet"):
        assert _file_completeness(d / "leaderboard" / name) == comp


def test_league_run_json_is_one_document(reference, capsys):
    """``league run --json`` on a finished league (resumed: nothing left to run): one document on
    stdout, the leaderboard as ``league report --json`` gives it, the runs and the wall time; with
    ``-q`` no log line on stderr."""
    league, d, expected = reference  # (a league directory cannot be moved: its campaigns name it)
    argv = _run(league, d, "--seeds", "2", "--json")
    t0 = time.perf_counter()
    assert main(argv) == 0
    wall = time.perf_counter() - t0
    captured = capsys.readouterr()
    doc = json.loads(captured.out)  # one document, nothing else on stdout
    assert "lqr: " in captured.err  # the log stays on stderr
    assert set(doc) == {"league", "dir", "leaderboard", "units", "outputs", "runs", "failed", "methods", "wall_time"}  # fmt: skip
    assert doc["runs"] == len(expected) == 28 and doc["failed"] == 0
    assert [m["name"] for m in doc["methods"]] == ["lqr"]
    assert 0 < doc["methods"][0]["wall_time"] <= doc["wall_time"] <= wall
    assert doc["units"]["wall_time"] == "s" and doc["units"]["pass_rate"] == "1"
    assert doc["leaderboard"]["complete"] is True
    assert doc["leaderboard"]["ranking"].keys() == {"unsaturated", "limited"}
    for path in doc["outputs"].values():
        assert Path(path).is_file(), path
    assert main(["-q", *argv]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["runs"] == 28 and "lqr: " not in captured.err


def test_league_report_of_a_mistyped_tuning_result_exits_2(tmp_path, reference, capsys):
    """The tuned column reads DIR/tuned/*.json: a tuning result with a field of the wrong type is named
    (another program's JSON file there is skipped, as before)."""
    d = _league_copy(reference, tmp_path)
    (d / "tuned").mkdir()
    (d / "tuned" / "notes.json").write_text('{"mine": 1}')
    result = {
        "kind": "formation-ftc tuning",
        "method": "lqr",
        "level": "limited",
        "tuned_gains": {"controller.max_position_error": "large"},
        "paper_gains": {"controller.max_position_error": 1.0},
        "objective": {"metric": "delta_v_total", "units": "m s-1", "statistic": "mean"},
        "holdout": {"paper": {"pass_rate": 0.5}, "tuned": {"pass_rate": 1.0}},
        "optimiser": {"name": "nelder-mead"},
    }
    path = d / "tuned" / "lqr--limited.json"
    path.write_text(json.dumps(result))
    assert main(["league", "report", str(d), "--no-plots"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(
        f"error: tuning result {path}: field tuned_gains.controller.max_position_error: "
        "Input should be a valid number"
    ), err
    result["tuned_gains"] = {"controller.max_position_error": 2.0}
    path.write_text(json.dumps(result))
    assert main(["league", "report", str(d), "--no-plots", "--json"]) == 0
    row = json.loads(capsys.readouterr().out)["leaderboard"]["ranking"]["limited"][0]
    assert row["tuning"]["gains"] == {"controller.max_position_error": 2.0}
