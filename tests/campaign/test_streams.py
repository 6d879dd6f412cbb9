"""Vectorised per-run streams reproduce NumPy's SeedSequence / PCG64 / Generator draws bit for bit."""

from __future__ import annotations

import zlib

import numpy as np
import pytest

from formation_ftc.campaign import make_plan, sampling, streams
from formation_ftc.campaign.sampling import (
    RunInputs,
    draw_value,
    draw_values,
    run_seed,
    run_seeds,
)
from formation_ftc.campaign.spec import Choice, Integer, LogUniform, Normal, Uniform

# keys spread over the whole spawn-key range (run ids / replicates), including the edges
KEYS = np.unique(
    np.concatenate(
        [
            np.arange(0, 300),
            np.random.default_rng(0).integers(0, 2**32 - 1, 300),
            [2**31 - 1, 2**31, 2**32 - 2, 2**32 - 1],
        ]
    )
)


@pytest.mark.parametrize("entropy", [0, 1, 2026, 2**32 - 1, 2**32, 2**70 + 12345])
@pytest.mark.parametrize(
    "suffix", [(0,), (1, 0), (1, 0xFFFFFFFF), (1, zlib.crc32(b"controller.kp"))]
)
def test_seed_states_equal_numpy_seed_sequence(entropy, suffix):
    ref = np.array(
        [
            np.random.SeedSequence(entropy, spawn_key=(int(k), *suffix)).generate_state(8)
            for k in KEYS
        ]
    )
    assert np.array_equal(streams.seed_states(entropy, KEYS, suffix, 8), ref)


@pytest.mark.parametrize("entropy", [3, 2026, 2**40 + 1])
def test_pcg64_state_and_first_double_equal_numpy(entropy):
    suffix = (1, 77)
    hi, lo, ihi, ilo = streams.pcg64_states(streams.seed_states(entropy, KEYS, suffix, 8))
    d = streams.first_doubles(entropy, KEYS, suffix)
    for n, k in enumerate(KEYS.tolist()):
        bg = np.random.PCG64(np.random.SeedSequence(entropy, spawn_key=(k, *suffix)))
        st = bg.state["state"]
        assert (int(hi[n]) << 64 | int(lo[n])) == st["state"] and (
            int(ihi[n]) << 64 | int(ilo[n])
        ) == st["inc"]
        assert d[n] == np.random.Generator(bg).random()


def test_run_seeds_equal_run_seed():
    assert run_seeds(2026, KEYS).tolist() == [run_seed(2026, int(k)) for k in KEYS]
    assert run_seeds(2**33 + 9, KEYS[:50]).tolist() == [
        run_seed(2**33 + 9, int(k)) for k in KEYS[:50]
    ]


@pytest.mark.parametrize(
    "sampler",
    [
        Uniform("a.b", 1.0, 4.0),
        Uniform("x", -3.5e-7, 2.25e9),
        LogUniform("a.c", 1e-3, 50.0),
        Normal("a.d", 100.0, 5.0),
        Normal("a.e", 100.0, 5.0, 80.0, 120.0),
        Normal("a.f", 0.0, 1.0, None, 0.5),
        Integer("a.g", -3, 17),
        Integer("a.h", 0, 2**40),
        Choice("a.i", ("pd", "lqr", {"k": [1, 2]})),
        Choice("a.j", (1.0, 2.0, 3.0), (0.2, 0.5, 0.3)),
    ],
)
def test_draw_values_equal_per_run_generators(sampler):
    got = draw_values(sampler, 2026, KEYS)
    ref = [draw_value(sampler, 2026, int(k)) for k in KEYS]
    assert [type(v) for v in got] == [type(v) for v in ref]
    assert got == ref  # exact: same floats, ints and objects


def test_draw_values_fall_back_when_the_stream_module_disagrees(monkeypatch):
    # a (simulated) NumPy whose seeding differs: the check on the first keys sends every run to NumPy
    monkeypatch.setattr(streams, "first_doubles", lambda e, k, s: np.full(len(k), 0.5))
    monkeypatch.setattr(sampling, "_CHECKED_SAMPLERS", set())
    s = Uniform("a.b", 1.0, 4.0)
    assert draw_values(s, 7, KEYS[:40]) == [draw_value(s, 7, int(k)) for k in KEYS[:40]]


@pytest.mark.parametrize(
    "fields",
    [
        dict(paired=False),
        dict(paired=True),
        dict(sampling="sobol"),
        dict(sampling="lhs", paired=False),
    ],
)
def test_run_columns_equal_run_inputs(tiny, fields):
    plan = make_plan(tiny(runs=7, **fields))
    ids = [13, 0, 6, 7, 2, 9, 8]
    ref = [_inputs_by_hand(plan, r) for r in ids]
    assert [plan.run_inputs(r) for r in ids] == ref and plan.run_inputs_many(ids) == ref
    cols = plan.run_columns(ids)
    assert cols.seed.tolist() == [i.seed for i in ref] and cols.run_id.tolist() == ids
    assert cols.rows(plan.base_names) == ref


def _inputs_by_hand(plan, r: int) -> RunInputs:
    """Run ``r``'s inputs by the rules of formation_ftc.campaign.sampling's docstring, one run at a
    time with NumPy's own generators."""
    g, j = divmod(r, plan.runs)
    j += plan.first_replicate
    key = j if plan.paired else r
    b, values = plan.grid_point(g)
    for m, s in enumerate(plan.random_samplers):
        if plan.sampling == "random":
            values[s.path] = draw_value(s, plan.seed, key)
        else:
            values[s.path] = sampling.value_from_unit(s, plan.design()[key][m])
    ordered = {s.path: values[s.path] for s in plan.samplers}
    return RunInputs(r, g, j, run_seed(plan.seed, key), plan.base_names[b], ordered)
