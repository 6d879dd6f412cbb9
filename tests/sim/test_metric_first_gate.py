"""The ``first`` reduction and the ``gate`` of sim.metrics against a direct numpy evaluation of the
same sample sequence (every sample folded in, as the closed loop does)."""

import jax.numpy as jnp
import numpy as np
import pytest

from formation_ftc.sim.metrics import Metric, finalize, init_accumulators, update_accumulators

DT = 0.1


def _fold(metrics, samples):
    """samples: list of signal dicts at t = k DT; the last one is the horizon sample."""
    acc = init_accumulators(metrics, samples[0])
    for k, sig in enumerate(samples):
        acc = update_accumulators(
            metrics, acc, jnp.asarray(k * DT), DT, sig, is_final=k == len(samples) - 1
        )
    return [np.asarray(v) for v in finalize(metrics, acc)]


def test_first_time_at_or_above_threshold():
    x = np.array([0.0, 1.0, 0.5, 2.0, 2.0, 1.0])
    m = [
        Metric("first", "x", reduce="first", threshold=2.0),
        Metric("first_late", "x", reduce="first", threshold=0.9, start=0.25),
        Metric("never", "x", reduce="first", threshold=5.0),
    ]
    got = _fold(m, [{"x": jnp.asarray(v)} for v in x])
    t = np.arange(x.size) * DT
    assert got[0] == pytest.approx(t[np.argmax(x >= 2.0)])
    assert got[1] == pytest.approx(t[np.argmax((x >= 0.9) & (t >= 0.25))])  # 0.3 s, not 0.1 s
    assert np.isnan(got[2])


def test_gate_opens_the_window_on_a_signal():
    rng = np.random.default_rng(1)
    e = rng.normal(size=(12, 2, 3))  # (time, pair, axis)
    gate = np.array([0, 0, 1, 1, 0, 1, 1, 1, 0, 0, 1, 0], bool)
    samples = [{"e": jnp.asarray(e[k]), "g": jnp.asarray(gate[k])} for k in range(12)]
    m = [
        Metric("gmax", "e", reduce="max", norm=True, norm_ord="inf", spacecraft="max", gate="g"),
        Metric("gmean", "e", reduce="mean", component=1, spacecraft="max", gate="g", start=0.55),
        Metric("closed", "e", reduce="max", norm=True, spacecraft="max", gate="g", end=0.15),
    ]
    got = _fold(m, samples)
    assert got[0] == pytest.approx(np.max(np.abs(e[gate])))
    t = np.arange(12) * DT
    sel = gate & (t >= 0.55 - 1e-9)
    assert got[1] == pytest.approx(np.mean(np.max(e[sel][:, :, 1], axis=1)))
    assert np.isnan(got[2])  # the gate never opens inside [0, 0.15]: no sample, NaN


def test_gate_not_allowed_with_stage_reductions():
    with pytest.raises(ValueError, match="gate"):
        Metric("x", "e", reduce="stage_integral", gate="g")
