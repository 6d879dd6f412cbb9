"""Campaign store under faults: a second writer is refused while the first goes on unharmed, a stale
lock of a dead process is taken over, a flipped byte in a finished chunk is detected (report refuses,
resume recomputes), and the worker processes of a campaign killed with SIGKILL do not outlive it."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

from formation_ftc.campaign import CampaignError, CampaignStore, make_plan, run_campaign
from formation_ftc.campaign.cli import main as campaign_main


def _table(plan, chunk_id):
    ids = plan.chunk(chunk_id).run_ids
    return pd.DataFrame(
        {"run_id": ids, "status": ["ok"] * len(ids), "metric:x": [float(i) for i in ids]}
    )


# ------------------------------------------------------------------------------------------- lock
def test_second_store_is_refused_naming_host_and_pid(tmp_path, tiny):
    plan = make_plan(tiny(runs=3, chunk_size=2))
    root = tmp_path / "c"
    first = CampaignStore.prepare(root, plan)
    first.initialize()
    try:
        second = CampaignStore.prepare(root, plan)
        with pytest.raises(
            CampaignError,
            match=rf"in use by another campaign run \(host {socket.gethostname()}, "
            rf"PID {os.getpid()}",
        ):
            second.initialize()
        first.write_chunk(0, _table(plan, 0))  # the first writer is unharmed
    finally:
        first.close()
    again = CampaignStore.prepare(root, plan)
    again.initialize()  # released: the next run takes it
    assert again.finished() == {0}
    again.close()


def test_stale_lock_of_a_dead_process_is_taken_over(tmp_path, tiny):
    plan = make_plan(tiny(runs=3, chunk_size=2))
    root = tmp_path / "c"
    s = CampaignStore.prepare(root, plan)
    s.initialize()
    s.write_chunk(1, _table(plan, 1))
    s.close()
    # what a run killed with SIGKILL leaves: the text of the lock, but no lock held (the kernel freed it)
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True
    )
    (root / ".lock").write_text(json.dumps({"host": socket.gethostname(), "pid": int(dead.stdout)}))
    tmp = root / "chunks" / f".chunk-000002.parquet.tmp-{int(dead.stdout)}"
    tmp.write_bytes(b"half written")
    s2 = CampaignStore.prepare(root, plan)
    s2.initialize()
    try:
        holder = json.loads((root / ".lock").read_text())
        assert holder["pid"] == os.getpid() and not tmp.exists()
        assert s2.finished() == {1}
    finally:
        s2.close()


def _slow_campaign(tiny, write_campaign, path: Path, n_chunks=8, horizon=2000.0, **campaign):
    raw = tiny(runs=2 * n_chunks, chunk_size=2, metrics=["final_position_error_mean"], **campaign)
    raw["overrides"]["simulation.horizon"] = horizon
    raw["sample"].pop("controller.kd")
    raw["traces"]["runs"] = []
    return raw, write_campaign(path, raw)


def _n_chunks(out: Path) -> int:
    d = out / "chunks"
    return len([p for p in d.iterdir() if p.name.endswith(".parquet")]) if d.exists() else 0


@pytest.mark.slow
def test_second_writer_is_refused_and_the_first_finishes(tmp_path, tiny, write_campaign, capsys):
    raw, spec = _slow_campaign(
        tiny, write_campaign, tmp_path / "slow.toml", n_chunks=12, horizon=6000.0
    )
    out = tmp_path / "out"
    first = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "formation_ftc.campaign.cli",
            "run",
            str(spec),
            "--out",
            str(out),
            "--no-progress",
            "--workers",
            "1",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    try:
        deadline = time.monotonic() + 240
        while _n_chunks(out) == 0 and first.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        assert first.poll() is None, first.stderr.read().decode()[-2000:]
        for _ in range(2):  # the scan of a second writer deletes nothing; its run is refused
            assert (
                campaign_main(
                    ["run", str(spec), "--out", str(out), "--no-progress", "--workers", "1"]
                )
                == 2
            )
            err = capsys.readouterr().err
            assert (
                f"in use by another campaign run (host {socket.gethostname()}, PID {first.pid}"
                in err
            )
        assert first.poll() is None, "the first writer finished before the second one tried"
        _, err = first.communicate(timeout=500)
        assert first.returncode == 0, err.decode()[-2000:]
    finally:
        if first.poll() is None:
            first.kill()
            first.wait()
    results = CampaignStore.read(out).load_results()
    assert results["run_id"].tolist() == list(range(24))


# -------------------------------------------------------------------------------------- checksum
def _flip_metric_byte(path: Path, value: float) -> None:
    data = bytearray(path.read_bytes())
    pos = bytes(data).find(np.float64(value).tobytes())
    assert pos > 0, "metric value not found in the file"
    data[pos + 6] ^= 0x01  # one bit of the exponent/mantissa of that metric value
    path.write_bytes(bytes(data))


def test_flipped_byte_in_a_metric_is_detected_and_recomputed(tmp_path, tiny, capsys):
    raw = tiny()
    raw["traces"]["runs"] = []  # no traced runs: a program of their own, and no metric in them
    out = tmp_path / "c"
    first = run_campaign(raw, out).results
    chunk = out / "chunks" / "chunk-000001.parquet"
    col = "metric:max_position_error"
    value = float(pq.read_table(chunk).to_pandas()[col].iloc[0])
    _flip_metric_byte(chunk, value)
    # the report refuses the directory, naming the chunk (exit 2)
    assert campaign_main(["report", str(out), "--no-plots"]) == 2
    err = capsys.readouterr().err
    assert "chunk-000001.parquet: content does not match its checksum" in err
    # resuming recomputes that chunk only and reports it; the numbers are the original ones
    again = run_campaign(raw, out)
    assert again.chunks_computed == 1 and again.chunks_resumed == again.chunks_total - 1
    assert "chunk-000001.parquet: content does not match its checksum" in capsys.readouterr().err
    pd.testing.assert_frame_equal(again.results, first)
    manifest = json.loads((out / "manifest.json").read_text())
    assert set(manifest["chunk_sha256"]) == {str(c) for c in range(again.chunks_total)}


# ---------------------------------------------------------------------------------------- orphans
def _children(pid: int) -> set[int]:
    """Every live descendant of ``pid`` (from /proc)."""
    parents: dict[int, int] = {}
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                stat = (d / "stat").read_text()
            except OSError:
                continue
            parents[int(d.name)] = int(stat[stat.rindex(")") + 2 :].split()[1])
    out, frontier = set(), {pid}
    while frontier:
        nxt = {c for c, p in parents.items() if p in frontier and c not in out}
        out |= nxt
        frontier = nxt
    return out


def _alive(pid: int) -> bool:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rindex(")") + 2] != "Z"  # a zombie has exited


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.parametrize(
    "executor", [["--workers", "2"], ["--dask-local", "2"]], ids=["pool", "dask-local"]
)
def test_workers_die_with_a_killed_campaign(tmp_path, tiny, write_campaign, executor):
    _, spec = _slow_campaign(
        tiny, write_campaign, tmp_path / "orphan.toml", n_chunks=40, horizon=4000.0
    )
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "formation_ftc.campaign.cli",
            "run",
            str(spec),
            "--out",
            str(out),
            "--no-progress",
            *executor,
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    workers: set[int] = set()
    try:
        deadline = time.monotonic() + 240
        while time.monotonic() < deadline and proc.poll() is None:
            workers |= _children(proc.pid)
            if _n_chunks(out) >= 1:  # the workers are computing
                break
            time.sleep(0.1)
        workers |= _children(proc.pid)
        assert proc.poll() is None and len(workers) >= 2, proc.stderr.read().decode()[-2000:]
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and any(_alive(w) for w in workers):
            time.sleep(0.2)
        left = [w for w in workers if _alive(w)]
        assert not left, f"worker processes {left} outlived the killed campaign"
    finally:
        for w in workers:
            if _alive(w):
                os.kill(w, signal.SIGKILL)
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_file_system_without_locks_is_named(tmp_path, tiny, monkeypatch):
    import errno

    fcntl = pytest.importorskip("fcntl")  # what filelock locks with on POSIX

    def no_locks(fd, op):
        raise OSError(errno.ENOLCK, "No locks available")

    monkeypatch.setattr(fcntl, "flock", no_locks)
    plan = make_plan(tiny(runs=3, chunk_size=2))
    store = CampaignStore.prepare(tmp_path / "c", plan)
    with pytest.raises(
        CampaignError, match="refuses advisory locks on .lock \\(No locks available\\)"
    ):
        store.initialize()
