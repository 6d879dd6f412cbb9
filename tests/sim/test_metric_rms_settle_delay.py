"""The ``rms`` and ``settle_delay`` metric reductions against direct numpy computations."""

import jax.numpy as jnp
import numpy as np

from formation_ftc.sim.metrics import Metric, finalize, init_accumulators, update_accumulators


def _run(metrics, values, dt):
    """Fold samples k = 0..n-1, then the horizon sample n (is_final), as the closed loop does."""
    sig = {"s": jnp.asarray(values[0])}
    acc = init_accumulators(metrics, sig)
    n = len(values) - 1
    for k in range(n):
        acc = update_accumulators(metrics, acc, k * dt, dt, {"s": jnp.asarray(values[k])})
    acc = update_accumulators(metrics, acc, n * dt, dt, {"s": jnp.asarray(values[n])}, is_final=True)
    return [float(v) for v in finalize(metrics, acc)]


def test_rms_over_window_excludes_horizon_sample():
    rng = np.random.default_rng(0)
    v = rng.normal(size=101)
    v[-1] = 1e6  # the horizon sample is never counted
    dt = 0.1
    (whole, window, empty) = _run([Metric("a", "s", reduce="rms"), Metric("b", "s", reduce="rms", start=2.0, end=7.0),
                                   Metric("c", "s", reduce="rms", start=20.0)], v, dt)
    np.testing.assert_allclose(whole, np.sqrt(np.mean(v[:100] ** 2)), rtol=1e-14)
    np.testing.assert_allclose(window, np.sqrt(np.mean(v[20:71] ** 2)), rtol=1e-14)  # inclusive edges
    assert np.isnan(empty)


def test_settle_delay_is_settle_time_from_window_start():
    dt = 0.5
    v = np.array([5.0, 0.1, 3.0, 2.0, 0.5, 0.2, 0.1, 0.05, 0.0, 0.0, 0.0])
    thr = 1.0
    settle, delay, never, small, above = _run([
        Metric("a", "s", reduce="settle", threshold=thr, start=1.0),
        Metric("b", "s", reduce="settle_delay", threshold=thr, start=1.0),
        Metric("c", "s", reduce="settle_delay", threshold=thr, start=2.5),   # never above in its window
        Metric("d", "s", reduce="settle_delay", threshold=0.01, start=1.0),
        Metric("e", "s", reduce="settle_delay", threshold=0.0, start=1.0),   # never below: NaN
    ], v, dt)
    for got, th in ((delay, thr), (small, 0.01)):
        k_last = max(k for k in range(2, len(v)) if v[k] >= th)  # window starts at k = 2 (t = 1.0)
        assert got == (k_last + 1) * dt - 1.0
    assert settle == delay + 1.0
    assert never == 0.0
    assert np.isnan(above)
