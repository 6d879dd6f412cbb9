"""Dask on loopback only: an address that answers but is not a Dask scheduler fails within the
connect timeout (never a hang), and a real cluster -- ``dask scheduler`` plus two ``dask worker``
processes, as a cluster user starts them -- finishes a campaign run from the command line with every
run exactly once and the local numbers, although one worker is killed with SIGKILL mid-campaign."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pandas as pd
import pytest

from formation_ftc.campaign import CampaignError, DaskExecutor, run_campaign
from formation_ftc.campaign.cli import main as campaign_main

DASK = Path(sys.executable).with_name("dask")


class _SilentServer:
    """A TCP server on 127.0.0.1 that accepts connections, reads, and never answers (like a web
    server waiting for the end of an HTTP request line)."""

    def __init__(self):
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(8)
        self.port = self.sock.getsockname()[1]
        self.conns: list[socket.socket] = []
        self._stop = False
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self):
        self.sock.settimeout(0.2)
        while not self._stop:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                continue
            self.conns.append(conn)

    def close(self):
        self._stop = True
        self.thread.join(2)
        for c in self.conns:
            c.close()
        self.sock.close()


def _raw(runs=3, horizon=20.0):
    return {
        "campaign": {
            "name": "dask-hard",
            "base": "cw-pd-fault",
            "runs": runs,
            "seed": 5,
            "chunk_size": 2,
            "metrics": ["final_position_error_mean", "delta_v_total"],
        },
        "overrides": {"simulation.horizon": horizon},
        "sample": {"controller.kp": {"dist": "uniform", "low": 1.0, "high": 3.0}},
    }


def test_not_a_scheduler_fails_within_the_timeout_naming_the_address(tmp_path):
    server = _SilentServer()
    addr = f"tcp://127.0.0.1:{server.port}"
    try:
        t0 = time.monotonic()
        with pytest.raises(
            CampaignError, match=rf"--scheduler {addr}: no Dask scheduler handshake within 2 s"
        ):
            run_campaign(
                _raw(),
                tmp_path / "never",
                executor=DaskExecutor(scheduler=addr, connect_timeout=2.0),
            )
        assert time.monotonic() - t0 < 15
        assert not (tmp_path / "never").exists()
        # the command line: exit status 2 and one line naming the address, within the timeout
        spec = tmp_path / "c.toml"
        import tomli_w

        spec.write_text(tomli_w.dumps(_raw()))
        t0 = time.monotonic()
        code = campaign_main(
            [
                "run",
                str(spec),
                "--out",
                str(tmp_path / "cli"),
                "--scheduler",
                addr,
                "--connect-timeout",
                "2",
                "--no-progress",
            ]
        )
        assert code == 2 and time.monotonic() - t0 < 30
    finally:
        server.close()


def test_connect_timeout_is_validated():
    with pytest.raises(CampaignError, match="--connect-timeout must be > 0"):
        DaskExecutor(scheduler="tcp://127.0.0.1:8786", connect_timeout=0.0)


def _start(cmd, log):
    return subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)


def _kill(proc):
    if proc.poll() is None:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.wait(10)


@pytest.mark.slow
def test_real_cluster_survives_a_killed_worker_and_equals_local(tmp_path):
    if not DASK.exists():  # pragma: no cover - dask is a dependency of the test environment
        pytest.fail(f"{DASK} not found: the dask command line is needed for this test")
    import tomli_w

    raw = _raw(runs=16, horizon=1000.0)  # 8 chunks of 2 runs, 10,000 steps each
    spec = tmp_path / "cluster.toml"
    spec.write_text(tomli_w.dumps(raw))
    sched_file = tmp_path / "scheduler.json"
    log = open(tmp_path / "cluster.log", "wb")  # noqa: SIM115 - closed in finally
    procs = []
    try:
        procs.append(
            _start(
                [
                    str(DASK),
                    "scheduler",
                    "--host",
                    "127.0.0.1",
                    "--port",
                    "0",
                    "--no-dashboard",
                    "--scheduler-file",
                    str(sched_file),
                ],
                log,
            )
        )
        deadline = time.monotonic() + 60
        while not sched_file.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        assert sched_file.exists(), (tmp_path / "cluster.log").read_text()[-2000:]
        time.sleep(0.2)
        address = json.loads(sched_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        workers = [
            _start(
                [
                    str(DASK),
                    "worker",
                    "--scheduler-file",
                    str(sched_file),
                    "--nthreads",
                    "1",
                    "--no-nanny",
                    "--host",
                    "127.0.0.1",
                    "--no-dashboard",
                    "--name",
                    f"w{i}",
                ],
                log,
            )
            for i in range(2)
        ]
        procs += workers
        from dask.distributed import Client

        with Client(address, timeout="30s") as c:
            c.wait_for_workers(2, timeout=90)
        out = tmp_path / "out"
        env = dict(os.environ, PYTHONUNBUFFERED="1")
        run = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "formation_ftc.cli",
                "campaign",
                "run",
                str(spec),
                "--out",
                str(out),
                "--scheduler",
                address,
                "--no-progress",
            ],
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        procs.append(run)
        deadline = time.monotonic() + 240
        chunks = out / "chunks"
        while time.monotonic() < deadline and run.poll() is None:
            if chunks.exists() and any(p.name.endswith(".parquet") for p in chunks.iterdir()):
                break
            time.sleep(0.05)
        n_done_at_kill = len([p for p in chunks.iterdir() if p.name.endswith(".parquet")])
        assert run.poll() is None and n_done_at_kill < 8, (
            "the campaign finished before a worker could be killed"
        )
        os.kill(workers[0].pid, signal.SIGKILL)  # one worker dies mid-campaign
        _, err = run.communicate(timeout=240)
        assert run.returncode == 0, err.decode()[-3000:]
        assert workers[0].wait(10) == -signal.SIGKILL
        assert workers[1].poll() is None  # the other worker finished the campaign
    finally:
        for p in reversed(procs):
            _kill(p)
        log.close()
    from formation_ftc.campaign import CampaignStore

    results = CampaignStore.read(out).load_results()
    assert results["run_id"].tolist() == list(range(16))  # every run exactly once
    local = run_campaign(raw, tmp_path / "local").results
    pd.testing.assert_frame_equal(results, local)
