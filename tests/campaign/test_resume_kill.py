"""A campaign killed with SIGKILL mid-way resumes: finished chunks are kept (not recomputed), none is
lost or duplicated, and the numbers equal an uninterrupted run's."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pandas as pd

from formation_ftc.campaign import run_campaign

N_CHUNKS = 8


def _chunks(out):
    d = out / "chunks"
    return {p.name: p for p in d.iterdir() if not p.name.startswith(".")} if d.exists() else {}


def test_sigkill_then_resume_equals_uninterrupted(tmp_path, tiny, write_campaign):
    raw = tiny(
        runs=2 * N_CHUNKS, chunk_size=2, metrics=["final_position_error_mean", "delta_v_total"]
    )
    raw["overrides"]["simulation.horizon"] = 2000.0  # 20,000 steps: ~0.3 s per chunk, time to kill
    raw["sample"].pop("controller.kd")  # no grid: one grid point, 8 chunks
    raw["traces"]["runs"] = [3]
    spec = write_campaign(tmp_path / "kill.toml", raw)
    out = tmp_path / "killed"
    env = dict(os.environ, PYTHONUNBUFFERED="1")
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
        ],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    deadline = time.monotonic() + 240
    while not _chunks(out) and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.005)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL, proc.stderr.read().decode()[-2000:]
    before = {name: (p.stat().st_mtime_ns, p.stat().st_ino) for name, p in _chunks(out).items()}
    assert 1 <= len(before) < N_CHUNKS, f"kill came too late/early: {sorted(before)}"

    resumed = run_campaign(spec, out)
    assert resumed.chunks_resumed == len(before) and resumed.chunks_computed == N_CHUNKS - len(
        before
    )
    after = _chunks(out)
    assert len(after) == N_CHUNKS
    for name, stamp in before.items():  # finished chunks were neither recomputed nor rewritten
        p = after[name]
        assert (p.stat().st_mtime_ns, p.stat().st_ino) == stamp
    assert not [p for p in (out / "chunks").iterdir() if p.name.startswith(".")]

    clean = run_campaign(spec, tmp_path / "clean")
    assert resumed.results["run_id"].tolist() == list(
        range(2 * N_CHUNKS)
    )  # none lost or duplicated
    pd.testing.assert_frame_equal(
        resumed.results, clean.results
    )  # same chunk size: identical numbers
    assert (out / "traces" / "run-000003.nc").exists()
