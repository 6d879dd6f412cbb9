"""Executors give the local numbers: a process pool (spawn) and a Dask LocalCluster of 2 workers
reproduce the in-process results exactly (same chunk size => same compiled program). An unreachable
or malformed scheduler address is an error before any run."""

from __future__ import annotations

import socket
import time

import pandas as pd
import pytest

from formation_ftc.campaign import CampaignError, DaskExecutor, LocalExecutor, run_campaign
from formation_ftc.campaign.executors import make_executor, parse_scheduler_address


@pytest.fixture(scope="module")
def local_result(tmp_path_factory):
    from formation_ftc.campaign.spec import load_campaign  # noqa: F401

    raw = _raw()
    return raw, run_campaign(raw, tmp_path_factory.mktemp("local") / "c").results


def _raw():
    return {
        "campaign": {
            "name": "exec",
            "base": "cw-pd-fault",
            "runs": 3,
            "seed": 5,
            "chunk_size": 2,
            "metrics": ["final_position_error_mean", "delta_v_total"],
        },
        "overrides": {"simulation.horizon": 20.0},
        "sample": {
            "controller.kp": {"dist": "uniform", "low": 1.0, "high": 3.0},
            "controller.kd": {"grid": [10.0, 30.0]},
        },
    }


def test_dask_local_cluster_equals_local(local_result, tmp_path):
    raw, local = local_result
    outcome = run_campaign(raw, tmp_path / "dask", executor=DaskExecutor(n_local=2))
    assert outcome.chunks_computed == 4
    pd.testing.assert_frame_equal(outcome.results, local)


def test_process_pool_equals_local(local_result, tmp_path):
    raw, local = local_result
    outcome = run_campaign(raw, tmp_path / "pool", executor=LocalExecutor(workers=2))
    pd.testing.assert_frame_equal(outcome.results, local)


def test_unreachable_scheduler_fails_fast_before_any_run(tmp_path):
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    out = tmp_path / "never"
    t0 = time.monotonic()
    with pytest.raises(
        CampaignError, match=rf"cannot reach the Dask scheduler at tcp://127.0.0.1:{port}"
    ):
        run_campaign(_raw(), out, executor=DaskExecutor(scheduler=f"tcp://127.0.0.1:{port}"))
    assert time.monotonic() - t0 < 30
    assert not out.exists()  # no manifest, no chunk


@pytest.mark.parametrize("addr", ["tcp://host-without-port", "http://1.2.3.4:8786", "tcp://:99"])
def test_malformed_scheduler_address(addr):
    with pytest.raises(CampaignError, match="expected tcp://HOST:PORT"):
        DaskExecutor(scheduler=addr)


def test_executor_options():
    assert parse_scheduler_address("10.0.0.5:8786") == ("10.0.0.5", 8786)
    assert isinstance(make_executor(), LocalExecutor)
    assert isinstance(make_executor(dask_local=2), DaskExecutor)
    with pytest.raises(CampaignError, match="--workers is for the local executor"):
        make_executor(workers=2, dask_local=2)
    with pytest.raises(CampaignError, match="--workers must be >= 1"):
        LocalExecutor(0)


def test_automatic_local_pool_size():
    """workers=None (the default of `campaign run`): in-process for small work, else one worker per core
    and never more workers than chunks."""
    from formation_ftc.campaign.executors import AUTO_POOL_MIN_RUN_STEPS, auto_workers

    assert auto_workers(AUTO_POOL_MIN_RUN_STEPS - 1, 40, cores=8) == 1
    assert auto_workers(3 * 10**8, 40, cores=2) == 2
    assert auto_workers(3 * 10**8, 3, cores=16) == 3
    ex = LocalExecutor()
    assert ex.describe() == "local (in-process)"
    ex.prepare(3 * 10**8, 40)
    assert ex.workers == auto_workers(3 * 10**8, 40)
    fixed = LocalExecutor(1)
    fixed.prepare(3 * 10**8, 40)
    assert fixed.workers == 1  # an explicit choice is kept


def test_campaign_outcome_names_the_executor(tmp_path):
    outcome = run_campaign(_raw(), tmp_path / "auto")  # tiny: the automatic choice stays in-process
    assert outcome.executor == "local (in-process)"


def test_in_process_pipeline_starts_the_next_chunk_before_finishing_one():
    """In-process with ``start``: chunk k+1 is started (dispatched) before chunk k is finished, and
    the results come back in chunk order."""
    events: list[tuple[str, int]] = []

    def start(plan, c):
        events.append(("start", c))
        return lambda: (events.append(("finish", c)), c)[1]

    got = list(LocalExecutor(1).map(None, None, [0, 1, 2], start=start))
    assert got == [0, 1, 2]
    assert events == [
        ("start", 0),
        ("start", 1),
        ("finish", 0),
        ("start", 2),
        ("finish", 1),
        ("finish", 2),
    ]


def test_in_process_pipeline_delivers_a_finished_chunk_before_a_start_error():
    def start(plan, c):
        if c == 1:
            raise RuntimeError("chunk 1 cannot start")
        return lambda: c

    it = LocalExecutor(1).map(None, None, [0, 1, 2], start=start)
    assert next(it) == 0  # chunk 0 was computed: it is delivered (and stored) first
    with pytest.raises(RuntimeError, match="chunk 1 cannot start"):
        next(it)


def test_pipelined_in_process_equals_chunk_by_chunk(local_result, tmp_path):
    """The pipelined in-process campaign (and its background writer) stores exactly what run_chunk
    computes chunk by chunk."""
    from formation_ftc.campaign.runner import make_plan, run_chunk

    raw, _ = local_result
    outcome = run_campaign(raw, tmp_path / "inproc", executor=LocalExecutor(1))
    plan = make_plan(raw)
    tables = [run_chunk(plan, c).table for c in plan.chunks()]
    expected = (
        pd.concat(tables, ignore_index=True)
        .sort_values("run_id", kind="stable")
        .reset_index(drop=True)
    )
    pd.testing.assert_frame_equal(outcome.results, expected, check_dtype=False)
    assert outcome.chunks_computed == plan.n_chunks
