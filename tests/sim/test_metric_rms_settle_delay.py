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
    acc = update_accumulators(
        metrics, acc, n * dt, dt, {"s": jnp.asarray(values[n])}, is_final=True
    )
    return [float(v) for v in finalize(metrics, acc)]


def test_rms_over_window_excludes_horizon_sample():
    rng = np.random.default_rng(0)
    v = rng.normal(size=101)
    v[-1] = 1e6  # the horizon sample is never counted
    dt = 0.1
    (whole, window, empty) = _run(
        [
            Metric("a", "s", reduce="rms"),
            Metric("b", "s", reduce="rms", start=2.0, end=7.0),
            Metric("c", "s", reduce="rms", start=20.0),
        ],
        v,
        dt,
    )
    np.testing.assert_allclose(whole, np.sqrt(np.mean(v[:100] ** 2)), rtol=1e-14)
    np.testing.assert_allclose(
        window, np.sqrt(np.mean(v[20:71] ** 2)), rtol=1e-14
    )  # inclusive edges
    assert np.isnan(empty)


def test_settle_delay_is_settle_time_from_window_start():
    dt = 0.5
    v = np.array([5.0, 0.1, 3.0, 2.0, 0.5, 0.2, 0.1, 0.05, 0.0, 0.0, 0.0])
    thr = 1.0
    settle, delay, never, small, above = _run(
        [
            Metric("a", "s", reduce="settle", threshold=thr, start=1.0),
            Metric("b", "s", reduce="settle_delay", threshold=thr, start=1.0),
            Metric(
                "c", "s", reduce="settle_delay", threshold=thr, start=2.5
            ),  # never above in its window
            Metric("d", "s", reduce="settle_delay", threshold=0.01, start=1.0),
            Metric("e", "s", reduce="settle_delay", threshold=0.0, start=1.0),  # never below: NaN
        ],
        v,
        dt,
    )
    for got, th in ((delay, thr), (small, 0.01)):
        k_last = max(k for k in range(2, len(v)) if v[k] >= th)  # window starts at k = 2 (t = 1.0)
        assert got == (k_last + 1) * dt - 1.0
    assert settle == delay + 1.0
    assert never == 0.0
    assert np.isnan(above)


def test_metrics_accumulated_together_equal_metrics_alone():
    # metrics of one reduction share one accumulator array; the values must equal those of each metric
    # accumulated on its own (scalar and per-spacecraft metrics, a gate, several reductions mixed)
    rng = np.random.default_rng(5)
    n, dt = 40, 0.25
    series = [
        {"v": jnp.asarray(rng.normal(size=(3, 2))), "g": jnp.asarray(float(k % 3 == 0))}
        for k in range(n + 1)
    ]
    ms = [
        Metric("a", "v", reduce="max", norm=True, spacecraft="max", start=1.0),
        Metric("b", "v", reduce="max", norm=True, spacecraft="each", end=6.0),
        Metric("c", "v", reduce="rms", component=1, norm=True, spacecraft="mean"),
        Metric("d", "v", reduce="max", component=0, spacecraft="sum", start=2.0, end=5.0),
        Metric(
            "e", "v", reduce="settle_delay", norm=True, spacecraft="max", threshold=1.5, start=3.0
        ),
        Metric("f", "v", reduce="mean", component=0, spacecraft="each", gate="g"),
        Metric("g", "v", reduce="final", component=1, spacecraft="max", end=7.0),
        Metric("h", "v", reduce="mean", norm=True, spacecraft="mean", gate="g"),
    ]

    def run(metrics):
        acc = init_accumulators(metrics, series[0])
        for k in range(n):
            acc = update_accumulators(metrics, acc, k * dt, dt, series[k])
        acc = update_accumulators(metrics, acc, n * dt, dt, series[n], is_final=True)
        return finalize(metrics, acc)

    together = run(ms)
    for m, got in zip(ms, together, strict=True):
        np.testing.assert_array_equal(np.asarray(got), np.asarray(run([m])[0]))
    # and one of them against numpy directly
    norms = np.array([np.max(np.linalg.norm(np.asarray(s["v"]), axis=1)) for s in series])
    assert float(together[0]) == np.max(norms[4:])
