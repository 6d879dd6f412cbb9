"""Disturbances and noise (pure JAX; seeded).

* :func:`sinusoidal` -- bounded bias + amplitude sin(omega t + phase) per channel
* :func:`gaussian_noise` -- zero-mean Gaussian sample with given standard deviation from a JAX key
* :func:`step_key` -- the per-step random key: ``fold_in(run_key, k)``, so a step's noise does not
  depend on how the run is chunked or batched (same seed, same numbers)
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from formation_ftc.core.timefunctions import sinusoid as sinusoidal  # bias + A sin(omega t + phase)

__all__ = ["sinusoidal", "gaussian_noise", "step_key", "run_key"]


def run_key(seed: int) -> jax.Array:
    """Root random key of a run."""
    return jax.random.PRNGKey(seed)


def step_key(key: jax.Array, k) -> jax.Array:
    """Key for step k derived from the run key."""
    return jax.random.fold_in(key, k)


def gaussian_noise(key: jax.Array, shape, std) -> jax.Array:
    """Zero-mean normal sample (float64) with standard deviation ``std`` (held over one step)."""
    return std * jax.random.normal(key, shape, dtype=jnp.float64)
