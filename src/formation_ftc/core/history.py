"""Fixed-memory history ring buffer for delayed signals and learning laws (pure JAX).

Used for time-varying communication delays (read s_j(t - T_ij(t)) with linear interpolation, Li2020
Thm 2) and learning laws at t - tau (Gui2022). The buffer lives in the ``lax.scan`` carry.

Layout: ``values`` has shape (capacity, *signal_shape); ``head`` is the index of the newest sample,
which corresponds to step ``k_newest``; samples are equally spaced by ``dt``. Times earlier than the
first pushed sample return the prehistory value (the initial sample, our choice).
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

__all__ = ["History", "history_init", "history_push", "history_read", "required_capacity"]


class History(NamedTuple):
    values: jnp.ndarray  # (capacity, *shape)
    head: jnp.ndarray  # int, index of newest sample
    # shadows tuple.count (a NamedTuple field by design; the method is never used on a History)
    count: jnp.ndarray  # type: ignore[assignment]  # int, number of samples pushed (saturates at capacity)


def required_capacity(max_delay: float, dt: float) -> int:
    """Samples needed to read back ``max_delay`` seconds with interpolation: ceil(T/dt) + 2."""
    if max_delay < 0:
        raise ValueError(f"max_delay must be >= 0 s, got {max_delay}")
    return int(jnp.ceil(max_delay / dt - 1e-9)) + 2


def history_init(initial, capacity: int) -> History:
    """Buffer filled with the initial sample (constant prehistory)."""
    initial = jnp.asarray(initial)
    values = jnp.broadcast_to(initial, (capacity,) + initial.shape).astype(initial.dtype)
    return History(values, jnp.asarray(0, dtype=jnp.int32), jnp.asarray(1, dtype=jnp.int32))


def history_push(h: History, value) -> History:
    """Append the sample of the next step."""
    cap = h.values.shape[0]
    head = (h.head + 1) % cap
    values = h.values.at[head].set(value)
    return History(values, head, jnp.minimum(h.count + 1, cap))


def history_read(h: History, lag_steps, mode: str = "linear"):
    """Sample ``lag_steps`` (float, >= 0) steps before the newest one.

    ``lag_steps`` may be an array: the result then has shape ``lag.shape + signal_shape`` when
    ``mode='linear'`` or ``'zoh'`` (zoh takes the older sample). Lags beyond the stored samples are
    clamped to the oldest stored sample (the prehistory value for a buffer that never wrapped).
    """
    cap = h.values.shape[0]
    lag = jnp.clip(
        jnp.asarray(lag_steps, dtype=h.values.dtype), 0.0, (h.count - 1).astype(h.values.dtype)
    )
    lo = jnp.floor(lag)
    frac = lag - lo
    lo_i = lo.astype(jnp.int32)
    hi_i = jnp.minimum(lo_i + 1, h.count - 1)
    newer = h.values[(h.head - lo_i) % cap]
    older = h.values[(h.head - hi_i) % cap]
    if mode == "zoh":
        return jnp.where((frac > 0)[(...,) + (None,) * (h.values.ndim - 1)], older, newer)
    if mode != "linear":
        raise ValueError(f"mode must be 'linear' or 'zoh', got {mode!r}")
    w = frac[(...,) + (None,) * (h.values.ndim - 1)]
    return (1.0 - w) * newer + w * older
