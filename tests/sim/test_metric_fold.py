"""Metrics folded a block of steps at a time (``fold_block``) against the sample-by-sample fold
(``update_accumulators``), which the other metric tests check against numpy and closed forms.

Tolerances: the selections (max, min, final, at, first, settle) pick one of the samples; the value of a
sample (a norm over a vector axis) is computed for the whole block at once, where XLA may add the
three squares in another order, so a picked value may differ by an ulp (1e-15 relative); the times
picked (first, settle) are exact. The sums (mean, integral, rms, block reductions) add a block's
samples first, then to the running sum -- another order of the same additions -- so they agree to a
few ulp of the sum's magnitude (1e-12 relative; the data are O(1) with at most a few hundred terms).
"""

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from formation_ftc.sim import metrics as mo
from formation_ftc.sim.metrics import Metric, finalize, init_accumulators, update_accumulators

SELECTIONS = ("max", "min", "final", "at", "first", "settle", "settle_delay")


@functools.cache
def _metrics():
    """Every reduction the block fold handles, with windows that open and close inside a block, gates,
    per-spacecraft values and block sizes smaller than, equal to and larger than a fold block."""
    ms = []
    for red in (
        "max",
        "min",
        "final",
        "at",
        "mean",
        "integral",
        "rms",
        "settle",
        "settle_delay",
        "first",
    ):
        ms += [
            Metric(f"{red}_all", "s", reduce=red, threshold=0.3),
            Metric(f"{red}_win", "s", reduce=red, start=3.7, end=11.3, threshold=0.5),
            Metric(
                f"{red}_each",
                "v",
                reduce=red,
                norm=True,
                spacecraft="each",
                start=1.0,
                threshold=1.2,
            ),
            Metric(f"{red}_gated", "s", reduce=red, gate="g", threshold=-0.2),
            Metric(
                f"{red}_gated_each",
                "v",
                reduce=red,
                component=2,
                spacecraft="each",
                gate="g",
                end=15.0,
            ),
        ]
    for red in ("block_rms", "block_dev_rms"):
        for block in (1, 7, 40):
            ms += [
                Metric(f"{red}_{block}", "s", reduce=red, block=block),
                Metric(f"{red}_{block}_win", "s", reduce=red, block=block, start=2.25, end=13.0),
                Metric(
                    f"{red}_{block}_each",
                    "v",
                    reduce=red,
                    component=0,
                    spacecraft="each",
                    block=block,
                    gate="g",
                ),
            ]
    ms.append(Metric("last_all", "s", reduce="last"))
    return tuple(ms)


@functools.cache
def _programs(ms, dt):
    """Compiled (step update, horizon update, block fold) of the metrics ``ms`` at step ``dt``, shared by
    the tests (a fold recompiles per block length)."""
    return (
        jax.jit(lambda a, t, x: update_accumulators(ms, a, t, dt, x)),
        jax.jit(lambda a, t, x: update_accumulators(ms, a, t, dt, x, is_final=True)),
        jax.jit(lambda a, k0, b: mo.fold_block(ms, a, k0, 0.0, dt, b)),
    )


def _series(n, rng):
    s = rng.normal(size=n + 1) + 0.1
    s[40:47] = 2.0  # above every threshold for a while, then below: a settle time inside the run
    v = rng.normal(size=(n + 1, 3, 3)) + 0.5
    g = (rng.uniform(size=n + 1) > 0.3).astype(float)
    g[:5] = 0.0
    return s, v, g


def _sequential(ms, s, v, g, dt):
    n = len(s) - 1
    sample = lambda k: {"s": jnp.asarray(s[k]), "v": jnp.asarray(v[k]), "g": jnp.asarray(g[k])}  # noqa: E731
    upd, final, _ = _programs(ms, dt)
    acc = init_accumulators(ms, sample(0))
    for k in range(n):
        acc = upd(acc, k * dt, sample(k))
    return final(acc, n * dt, sample(n))


def _folded(ms, s, v, g, dt, lengths):
    n = len(s) - 1
    sample = lambda k: {"s": jnp.asarray(s[k]), "v": jnp.asarray(v[k]), "g": jnp.asarray(g[k])}  # noqa: E731
    _, final, fold = _programs(ms, dt)
    acc = init_accumulators(ms, sample(0))
    k = 0
    for length in lengths:
        block = {
            "s": jnp.asarray(s[k : k + length]),
            "v": jnp.asarray(v[k : k + length]),
            "g": jnp.asarray(g[k : k + length]),
        }
        acc = fold(acc, jnp.asarray(k, jnp.int64), block)
        k += length
    assert k == n
    return final(acc, n * dt, sample(n))


def _flat(ms, acc):
    return mo.metrics_dict(ms, [np.asarray(x) for x in finalize(ms, acc)])


@functools.cache
def _nan_case():
    rng = np.random.default_rng(7)
    n, dt = 160, 0.1
    s, v, g = _series(n, rng)
    s[90] = np.nan  # a non-finite sample: every reduction must carry it as the per-step fold does
    ms = _metrics()
    return ms, s, v, g, dt, _flat(ms, _sequential(ms, s, v, g, dt))


#: a fold of a single sample, then three long folds whose boundaries fall inside windows and metric
#: blocks (each fold length is a program of its own, compiled once for the whole metric set: two here)
FOLD_LENGTHS = (1, 53, 53, 53)


def test_fold_block_equals_the_sample_by_sample_fold():
    ms, s, v, g, dt, want = _nan_case()
    got = _flat(ms, _folded(ms, s, v, g, dt, FOLD_LENGTHS))
    assert got.keys() == want.keys()
    checked_nan = checked_value = 0
    for name, w in want.items():
        m = next(x for x in ms if name == x.name or name.startswith(x.name + "_sc"))
        x = got[name]
        if np.isnan(w):
            assert np.isnan(x), name
            checked_nan += 1
            continue
        checked_value += 1
        if m.reduce in ("first", "settle", "settle_delay"):
            assert x == w, name  # the same sample's time, exactly
        elif m.reduce in SELECTIONS:
            assert x == pytest.approx(w, rel=1e-15, abs=0.0), name  # the same sample, to an ulp
        else:
            assert x == pytest.approx(w, rel=1e-12, abs=1e-15), name
    assert (
        checked_value > 80 and checked_nan > 0
    )  # the comparison covered values and NaN propagation


def test_fold_block_equals_the_sample_by_sample_fold_without_nan():
    # the NaN above poisons every unwindowed sum; without it every metric is a number
    rng = np.random.default_rng(11)
    n, dt = 160, 0.1
    s, v, g = _series(n, rng)
    ms = _metrics()
    want = _flat(ms, _sequential(ms, s, v, g, dt))
    got = _flat(ms, _folded(ms, s, v, g, dt, FOLD_LENGTHS))
    finite = [k for k, w in want.items() if np.isfinite(w)]
    assert len(finite) > 0.8 * len(want)
    for name in want:
        assert (np.isnan(got[name]) and np.isnan(want[name])) or got[name] == pytest.approx(
            want[name], rel=1e-12
        ), name


def test_block_metric_accumulators_equal_across_fold_boundaries():
    # the open boxcar block carries across fold blocks: same state as folding sample by sample
    rng = np.random.default_rng(3)
    n, dt = 50, 1.0
    s, v, g = _series(n, rng)
    ms = (
        Metric("b", "s", reduce="block_rms", block=7),
        Metric("d", "s", reduce="block_dev_rms", block=7),
    )
    seq = _sequential(ms, s, v, g, dt)
    fold = _folded(ms, s, v, g, dt, (3, 9, 5, 20, 13))
    for a, b in zip(jax.tree_util.tree_leaves(seq), jax.tree_util.tree_leaves(fold), strict=True):
        np.testing.assert_allclose(np.asarray(b), np.asarray(a), rtol=1e-12, atol=1e-14)


def test_closed_loop_metrics_folded_per_block_equal_the_per_step_fold():
    # gui2022-lof2tc reads every kind of step metric (max, final, at, mean, rms, settle, block
    # reductions); 2 s = 2000 steps in 20 records of 100 steps, folded in blocks of 50 and at every step
    from formation_ftc import api

    scenario = api.load_scenario("gui2022-lof2tc", {"simulation.horizon": 2.0})
    params = api.build_loop(scenario)
    assert params._metric_block() == 1  # a short run: the automatic choice folds at every step
    blocked = dataclasses.replace(params, metric_block=50)
    assert blocked._metric_block() == 50
    folded = jax.jit(lambda p: p.run())(blocked)
    stepwise = jax.jit(lambda p: p.run())(params)
    got, want = (
        mo.metrics_dict(params.metrics, [np.asarray(x) for x in out["metrics"]])
        for out in (folded, stepwise)
    )
    assert len(want) > 30
    for name, w in want.items():
        assert (np.isnan(w) and np.isnan(got[name])) or got[name] == pytest.approx(
            w, rel=1e-12, abs=1e-300
        ), name
    # the dynamics are the same program either way: records bit for bit
    for name, rec in stepwise["records"].items():
        np.testing.assert_array_equal(
            np.asarray(folded["records"][name]), np.asarray(rec), err_msg=name
        )


def test_automatic_metric_block_folds_long_runs_with_many_metrics():
    from formation_ftc import api
    from formation_ftc.sim.components import CompositionError

    lof2tc = api.build_loop(api.load_scenario("gui2022-lof2tc"))  # 42 metrics, 3e6 steps
    assert lof2tc.record_every == 100 and lof2tc._metric_block() == 50
    azizi = api.build_loop(api.load_scenario("azizi2009-llfr"))  # 7 metrics
    assert azizi._metric_block() == 1
    li2020 = api.build_loop(api.load_scenario("li2020-thm1"))  # records every 10 steps
    assert li2020.record_every == 10 and li2020._metric_block() == 1
    assert dataclasses.replace(li2020, metric_block=5)._metric_block() == 5
    with pytest.raises(
        CompositionError,
        match="metric_block = 3 must be 0 .automatic. or a divisor of record_every = 10",
    ):
        dataclasses.replace(li2020, metric_block=3).validate()


def test_folded_metrics_in_a_vmapped_batch_equal_the_batch_folded_per_step():
    # gui2022-lof2tc with and without an initial estimation error as one batch, its metrics folded in
    # blocks of 20 and at every step: the same batched dynamics (vmap may round them differently from a
    # run alone, so the reference is the same batch), the same metrics
    from formation_ftc import api
    from formation_ftc.sim.batch import batched_run, stack_params

    overrides = ({}, {"estimator.initial_estimate": [1.0, -1.0, 0.5, 0.01, -0.01, 0.005]})
    loops = [
        api.build_loop(api.load_scenario("gui2022-lof2tc", {"simulation.horizon": 1.0, **ov}))
        for ov in overrides
    ]
    outs = {}
    for block in (1, 20):
        batch, axes = stack_params([dataclasses.replace(p, metric_block=block) for p in loops])
        outs[block] = batched_run(dataclasses.replace(loops[0], metric_block=block), axes, 2)(batch)
    for name, rec in outs[1]["records"].items():
        np.testing.assert_array_equal(
            np.asarray(outs[20]["records"][name]), np.asarray(rec), err_msg=name
        )
    rows = []
    for r in range(2):
        got, want = (
            mo.metrics_dict(loops[0].metrics, [np.asarray(x)[r] for x in outs[b]["metrics"]])
            for b in (20, 1)
        )
        for name, w in want.items():
            assert (np.isnan(w) and np.isnan(got[name])) or got[name] == pytest.approx(
                w, rel=1e-12, abs=1e-300
            ), name
        rows.append(got)
    assert any(
        rows[0][n] != rows[1][n] for n in rows[0] if np.isfinite(rows[0][n])
    )  # two different runs
