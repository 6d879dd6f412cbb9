"""Delay line x(t - m dt) for discrete learning laws (pure JAX, lives in the scan carry).

A learning law ``x_k = G x_{k-m} + ...`` reads the value m steps back. ``m = 1`` keeps only the previous
sample (no indexing: the hot path when the learning interval equals the step); ``m > 1`` uses the ring
buffer of :mod:`formation_ftc.core.history`. The prehistory is constant: x_j = x_init for j < 0.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from formation_ftc.core.history import History, history_init, history_push, history_read

__all__ = ["DelayLine", "delay_init", "delay_read", "delay_push"]


class DelayLine(NamedTuple):
    """The last m samples of a signal: ``last`` when m = 1, ``ring`` otherwise (the other is None)."""

    last: jax.Array | None
    ring: History | None


def delay_init(prehistory, m: int) -> DelayLine:
    """Constant prehistory x(t) = prehistory for t < 0 (any shape)."""
    x0 = jnp.asarray(prehistory, dtype=jnp.float64)
    return DelayLine(x0, None) if m == 1 else DelayLine(None, history_init(x0, m))


def delay_read(line: DelayLine, m: int) -> jax.Array:
    """x_{k-m}: the sample m steps before the current one."""
    if m == 1:
        assert line.last is not None, "delay_read: m = 1 but the line holds a ring"
        return line.last
    assert line.ring is not None, "delay_read: m > 1 but the line holds no ring"
    return history_read(line.ring, m - 1, mode="zoh")


def delay_push(line: DelayLine, value, m: int) -> DelayLine:
    """Append x_k (end of step k)."""
    if m == 1:
        return DelayLine(value, None)
    assert line.ring is not None, "delay_push: m > 1 but the line holds no ring"
    return DelayLine(None, history_push(line.ring, value))
