"""The block (boxcar) metric reductions ``block_rms`` and ``block_dev_rms`` against numpy."""

import jax.numpy as jnp
import numpy as np
import pytest

from formation_ftc.sim.metrics import Metric, finalize, init_accumulators, update_accumulators


def _run(metrics, series, dt):
    """Fold samples k = 0..n-1, then the horizon sample n (is_final), as the closed loop does."""
    acc = init_accumulators(metrics, series[0])
    n = len(series) - 1
    for k in range(n):
        acc = update_accumulators(metrics, acc, k * dt, dt, series[k])
    acc = update_accumulators(metrics, acc, n * dt, dt, series[n], is_final=True)
    return [np.asarray(v) for v in finalize(metrics, acc)]


def _blocks(v: np.ndarray, block: int) -> np.ndarray:
    """The complete blocks of ``block`` samples of ``v`` (first axis), as rows."""
    nb = v.shape[0] // block
    return v[: nb * block].reshape((nb, block) + v.shape[1:])


def test_block_reductions_equal_numpy():
    rng = np.random.default_rng(1)
    n, dt, block = 203, 0.5, 4
    # a large mean, a period-2 chatter and noise: the chatter is what block_dev_rms measures
    v = 3e3 + 0.7 * (-1.0) ** np.arange(n + 1) + 0.01 * rng.normal(size=n + 1)
    v[-1] = 1e9  # the horizon sample is never counted
    series = [{"s": jnp.asarray(x)} for x in v]
    lo, hi = (
        10.0,
        80.0,
    )  # window [10, 80] s: samples k = 20..160 (141 samples: 35 blocks of 4, 1 dropped)
    ms = [
        Metric("a", "s", reduce="block_rms", block=block),
        Metric("b", "s", reduce="block_dev_rms", block=block),
        Metric("c", "s", reduce="block_rms", block=block, start=lo, end=hi),
        Metric("d", "s", reduce="block_dev_rms", block=block, start=lo, end=hi),
        Metric("e", "s", reduce="block_rms", block=1),
        Metric("f", "s", reduce="rms"),
        Metric("g", "s", reduce="block_rms", block=block, start=200.0),
    ]  # fewer samples than a block
    a, b, c, d, e, f, g = (float(x) for x in _run(ms, series, dt))
    whole, win = v[:n], v[20:161]
    assert a == pytest.approx(np.sqrt(np.mean(_blocks(whole, block).mean(axis=1) ** 2)), rel=1e-13)
    assert c == pytest.approx(np.sqrt(np.mean(_blocks(win, block).mean(axis=1) ** 2)), rel=1e-13)
    for got, x in ((b, whole), (d, win)):
        bl = _blocks(x, block)
        want = np.sqrt(np.mean((bl - bl.mean(axis=1, keepdims=True)) ** 2))
        assert got == pytest.approx(
            want, rel=1e-9
        )  # shifted sums: no cancellation against the 3e3 mean
        assert got == pytest.approx(0.7, rel=0.02)  # the chatter amplitude
    assert e == pytest.approx(f, rel=1e-14)  # blocks of one step: the plain rms
    assert np.isnan(g)


def test_block_reductions_per_spacecraft_gated_and_grouped():
    rng = np.random.default_rng(2)
    n, dt, block = 60, 1.0, 3
    vals = rng.normal(size=(n + 1, 2, 3))
    gate = (np.arange(n + 1) % 5 != 0).astype(float)
    series = [{"v": jnp.asarray(vals[k]), "g": jnp.asarray(gate[k])} for k in range(n + 1)]
    ms = [
        Metric("a", "v", reduce="block_rms", component=1, spacecraft="each", block=block),
        Metric(
            "b", "v", reduce="block_dev_rms", component=0, spacecraft="sum", block=block, gate="g"
        ),
        Metric("c", "v", reduce="block_rms", component=2, spacecraft="each", block=5, start=7.0),
        Metric("d", "v", reduce="max", norm=True, spacecraft="max"),
    ]
    together = _run(ms, series, dt)
    for m, got in zip(ms, together, strict=True):  # accumulated together == alone
        np.testing.assert_array_equal(got, _run([m], series, dt)[0])
    a, b, c, _ = together
    np.testing.assert_allclose(
        a, np.sqrt(np.mean(_blocks(vals[:n, :, 1], block).mean(axis=1) ** 2, axis=0)), rtol=1e-13
    )
    np.testing.assert_allclose(
        c, np.sqrt(np.mean(_blocks(vals[7:n, :, 2], 5).mean(axis=1) ** 2, axis=0)), rtol=1e-13
    )
    x = vals[:n, :, 0].sum(axis=1)[gate[:n] > 0]  # the gated samples form the blocks
    bl = _blocks(x, block)
    np.testing.assert_allclose(
        b, np.sqrt(np.mean((bl - bl.mean(axis=1, keepdims=True)) ** 2)), rtol=1e-12
    )


def test_block_reduction_needs_a_block():
    with pytest.raises(ValueError, match="needs block >= 1"):
        Metric("a", "s", reduce="block_rms")
