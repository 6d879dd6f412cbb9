"""Rotating regular-polygon formation and chain differences (deep-space formation of Azizi &
Khorasani 2009, Sec. V).

Desired formation: a regular N-gon of side ``side`` [m] (a square for N = 4) in the xy plane, rotating
counter-clockwise at ``omega`` [rad/s]; satellite i (0-based) sits on the circumscribed circle of radius
``side / (2 sin(pi / N))`` at angle ``omega t + pi/4 + i 2 pi / N``. Relative outputs are taken on the
chain of pairs (1, 2), (2, 3), ..., (N-1, N): ``chain_difference(x)[j] = x[j + 1] - x[j]``.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import jax
import jax.numpy as jnp

__all__ = ["rotating_polygon", "chain_difference", "relative_acceleration_fn"]


def rotating_polygon(t, n: int, n_axes: int, side, omega) -> tuple[jax.Array, jax.Array, jax.Array]:
    """Desired positions [m], velocities [m/s] and accelerations [m/s^2] at time ``t`` [s], each of
    shape (n, n_axes) (the first ``n_axes`` of x, y, z; z is 0)."""
    i = jnp.arange(n)
    radius = side / (2.0 * jnp.sin(jnp.pi / n))
    phase = omega * t + jnp.pi / 4 + i * (2.0 * jnp.pi / n)
    c, s = jnp.cos(phase), jnp.sin(phase)

    def in_plane(x, y):  # (n, n_axes) with the z component 0
        return jnp.stack([x, y, jnp.zeros_like(c)], axis=-1)[:, :n_axes]

    pos = in_plane(radius * c, radius * s)
    vel = in_plane(-radius * omega * s, radius * omega * c)
    return pos, vel, in_plane(-radius * omega**2 * c, -radius * omega**2 * s)


def chain_difference(x: jax.Array) -> jax.Array:
    """``x_{i+1} - x_i`` along the satellite axis (-2): (..., N, axes) -> (..., N-1, axes)."""
    return x[..., 1:, :] - x[..., :-1, :]


@functools.lru_cache(maxsize=64)
def relative_acceleration_fn(
    n: int, side: float, omega: float, axis: int
) -> Callable[[jax.Array], jax.Array]:
    """``t -> xdd_{i,i+1}^d(t)``: desired relative accelerations on the chain, one axis, shape (N-1,)
    [m/s^2]. Cached, so the same function object (a static argument of the FLFR design's H_i
    simulation) is reused."""

    def fn(t):
        _, _, acc = rotating_polygon(t, n, 3, side, omega)
        return acc[1:, axis] - acc[:-1, axis]

    return fn
