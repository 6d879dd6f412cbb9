"""Ring buffer: reads of delayed samples are exact for linear signals (linear interpolation)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from formation_ftc.core.history import history_init, history_push, history_read, required_capacity


def _filled(n_push, cap, dt=0.1):
    h = history_init(jnp.array([0.0, 1.0]), cap)
    for k in range(1, n_push + 1):
        t = k * dt
        h = history_push(h, jnp.array([t, 1.0 + 2 * t]))
    return h


def test_linear_signal_read_exactly():
    dt = 0.1
    h = _filled(30, required_capacity(1.0, dt), dt)
    t_now = 3.0
    for delay in [0.0, 0.05, 0.33, 0.999, 1.0]:
        v = history_read(h, delay / dt)
        np.testing.assert_allclose(v, [t_now - delay, 1 + 2 * (t_now - delay)], atol=1e-12)


def test_prehistory_is_initial_value():
    h = _filled(3, 20)
    np.testing.assert_allclose(history_read(h, 10.0), [0.0, 1.0])


def test_lag_matrix_broadcasts():
    h = _filled(10, 16)
    lags = jnp.array([[0.0, 1.5], [2.0, 3.25]])
    out = history_read(h, lags)
    assert out.shape == (2, 2, 2)
    np.testing.assert_allclose(out[1, 1, 0], 1.0 - 0.325, atol=1e-12)


def test_zoh_mode_and_jit_in_scan():
    def body(h, k):
        h = history_push(h, jnp.array([k * 1.0]))
        return h, history_read(h, 2.5, mode="zoh")

    h0 = history_init(jnp.array([0.0]), 8)
    _, reads = jax.lax.scan(body, h0, jnp.arange(1, 20))
    # zoh takes the older sample: k - 3
    np.testing.assert_allclose(reads[5:, 0], np.arange(6, 20) - 3.0)


def test_bad_mode_and_capacity():
    with pytest.raises(ValueError):
        history_read(_filled(2, 4), 1.0, mode="cubic")
    with pytest.raises(ValueError):
        required_capacity(-1, 0.1)
    assert required_capacity(3.6, 0.01) == 362
