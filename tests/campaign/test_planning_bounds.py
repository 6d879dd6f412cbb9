"""Planning a campaign of millions of runs takes bounded memory (issue 34, items 4 and 5): runs are
validated block by block with the same verdicts, chunks are made on access, the executor gets them a
window at a time, a quasi-Monte Carlo design too large to hold is refused naming --runs, and --workers
is capped by the cores and the memory."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from formation_ftc.campaign import cli as campaign_cli
from formation_ftc.campaign import runner, sampling
from formation_ftc.campaign.runner import make_plan
from formation_ftc.campaign.sampling import ChunkList
from formation_ftc.campaign.spec import CampaignError


def _validation_message(plan) -> str:
    with pytest.raises(CampaignError) as err:
        plan.validate_all()
    return str(err.value)


def test_validation_in_blocks_gives_the_verdicts_of_one_block(tiny, monkeypatch):
    raw = tiny(runs=40, chunk_size=8)
    raw["sample"]["controller.kp"] = {
        "dist": "normal",
        "mean": 0.5,
        "std": 1.0,
    }  # kp >= 0: some runs violate
    whole = _validation_message(make_plan(raw))
    assert "controller.kp" in whole and "run(s) in all" in whole
    monkeypatch.setattr(sampling, "VALIDATION_BLOCK", 3)
    assert _validation_message(make_plan(raw)) == whole
    make_plan(tiny(runs=40, chunk_size=8)).validate_all()  # valid samples stay valid in blocks


def test_validation_derives_one_block_of_runs_at_a_time(tiny, monkeypatch):
    plan = make_plan(tiny(runs=1000, chunk_size=8))
    monkeypatch.setattr(sampling, "VALIDATION_BLOCK", 256)
    sizes: list[int] = []
    derive = plan.run_columns
    monkeypatch.setattr(plan, "run_columns", lambda ids: sizes.append(len(ids)) or derive(ids))
    plan.validate_all()
    assert max(sizes) == 256 and sum(sizes) == plan.n_runs == 2000


def test_chunks_of_ten_million_runs_are_made_on_access():
    plan = make_plan("li2020-thm1-vs-sirftc", runs=10_000_000)
    tracemalloc.start()
    try:
        todo = plan.chunks(done={0, 5})
        first, last = todo[0], todo[-1]
        window = todo[1000:5096]
        steps = runner._run_steps(plan, todo[:10_000])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert plan.n_chunks == 400_000 and len(todo) == plan.n_chunks - 2
    assert (first.chunk_id, last.chunk_id) == (1, plan.n_chunks - 1) and last.stop == plan.n_runs
    assert isinstance(window, ChunkList) and len(window) == 4096 and window[0] == plan.chunk(1002)
    assert isinstance(plan.chunks().ids, range)
    assert steps == 10_000 * plan.chunk_size * plan.scenario(plan.run_inputs(0)).simulation.n_steps
    assert peak < 20 * 2**20  # bytes: 8 per pending chunk, not one object per chunk


def test_the_executor_gets_the_chunks_a_window_at_a_time(tiny, monkeypatch):
    plan = make_plan(tiny(runs=9, chunk_size=2))
    monkeypatch.setattr(runner, "MAP_WINDOW", 4)
    windows: list[list[int]] = []

    class Recorder:
        def map(self, fn, plan, chunks, start=None):
            windows.append([c.chunk_id for c in chunks])
            yield from (c.chunk_id for c in chunks)

    assert list(runner._map_in_windows(Recorder(), plan, plan.chunks(done={2}))) == [
        0,
        1,
        *range(3, 10),
    ]
    assert windows == [[0, 1, 3, 4], [5, 6, 7, 8], [9]]


@pytest.mark.parametrize(
    "sampling_kind, runs, allowed",
    [("sobol", 3_000_000, "2,097,152"), ("lhs", 3_000_000, "2,097,152")],
)
def test_a_design_too_large_to_hold_is_refused_naming_runs(tiny, sampling_kind, runs, allowed):
    raw = tiny(runs=10, sampling=sampling_kind)
    with pytest.raises(
        CampaignError, match=rf"--runs / campaign.runs = 3,000,000: .*1 <= runs <= {allowed} "
    ):
        make_plan(raw, runs=runs)
    raw["campaign"]["paired"] = (
        False  # one design row per run: the grid's 2 points share the budget
    )
    with pytest.raises(CampaignError, match=r"1 <= runs <= 1,048,576 "):
        make_plan(raw, runs=runs)
    assert make_plan(tiny(runs=10, sampling=sampling_kind), runs=4096).design().shape[0] == 4096


def test_workers_are_capped_with_one_warning_line(
    tiny, write_campaign, tmp_path, monkeypatch, capsys
):
    from formation_ftc.campaign import executors
    from formation_ftc.cli import main

    monkeypatch.setattr(executors, "schedulable_cpus", lambda: 2)
    asked: dict = {}

    def fake_make_executor(**kw):
        asked.update(kw)
        raise CampaignError("stopped before any worker starts")

    monkeypatch.setattr(executors, "make_executor", fake_make_executor)
    path = write_campaign(tmp_path / "c.toml", tiny())
    assert (
        main(["campaign", "run", str(path), "--out", str(tmp_path / "o"), "--workers", "32"]) == 2
    )
    assert asked["workers"] == 2
    warnings = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("warning:")]
    assert len(warnings) == 1 and "--workers: 32 worker processes asked for, using 2" in warnings[0]
    assert (
        campaign_cli._capped(1, "--workers", 0) == 1
        and campaign_cli._capped(None, "--workers", 0) is None
    )
    monkeypatch.setattr(executors, "available_memory", lambda: 3 * campaign_cli.WORKER_BYTES)
    assert campaign_cli._capped(2, "--dask-local", 2 * campaign_cli.WORKER_BYTES) == 1


def test_same_seed_same_numbers_whatever_the_block(tiny, monkeypatch):
    plan = make_plan(tiny(runs=50, chunk_size=7))
    ids = np.arange(plan.n_runs)
    whole = plan.run_columns(ids)
    monkeypatch.setattr(sampling, "VALIDATION_BLOCK", 7)
    parts = [plan.run_columns(b) for b in plan._run_id_blocks(None)]
    assert np.array_equal(np.concatenate([p.seed for p in parts]), whole.seed)
    for path, values in whole.values.items():
        assert [v for p in parts for v in p.values[path]] == values
