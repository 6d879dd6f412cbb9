"""Metric reductions: the infinity norm before the spacecraft and time reductions, and ``last`` (the
horizon value, read once after the loop)."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest

from formation_ftc.sim.metrics import Metric, finalize, init_accumulators, update_accumulators


def test_metric_inf_norm():
    """norm_ord = 'inf': largest absolute component before the spacecraft and time reductions."""
    met = (Metric("peak", "u", "max", norm=True, norm_ord="inf", spacecraft="max"),)
    samples = [
        np.array([[1.0, -4.0, 2.0], [0.5, 0.5, 0.5]]),
        np.array([[3.0, 0.0, 0.0], [0.0, 0.0, -3.5]]),
    ]
    acc = init_accumulators(met, {"u": samples[0]})
    for k, u in enumerate(samples):
        acc = update_accumulators(met, acc, 0.1 * k, 0.1, {"u": jnp.asarray(u)})
    assert float(finalize(met, acc)[0]) == 4.0
    with pytest.raises(ValueError, match="norm_ord"):
        Metric("bad", "u", norm=True, norm_ord="1")


def test_metric_last_is_the_horizon_value():
    """'last' ignores the steps (accumulator unchanged) and takes the horizon sample, like 'final'."""
    met = (Metric("end", "u", "last"), Metric("fin", "u", "final"))
    acc = init_accumulators(met, {"u": jnp.asarray(0.0)})
    for k, u in enumerate((3.0, -1.0, 7.0)):
        acc = update_accumulators(met, acc, 0.1 * k, 0.1, {"u": jnp.asarray(u)})
    assert np.isnan(float(finalize(met, acc)[0])) and float(finalize(met, acc)[1]) == 7.0
    acc = update_accumulators(met, acc, 0.3, 0.1, {"u": jnp.asarray(2.5)}, is_final=True)
    assert [float(v) for v in finalize(met, acc)] == [2.5, 2.5]
