"""Time-signal helpers shared by components: expression texts are static (part of the compile key),
compiled once per text (cached)."""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import jax.numpy as jnp

from formation_ftc.core.expressions import compile_vector_expression

__all__ = ["vector_expression", "spacecraft_numbers"]


@lru_cache(maxsize=1024)
def _compiled(texts: tuple[str, ...], field: str):
    return compile_vector_expression(texts, field)


def vector_expression(texts: Sequence[str], field: str, t, count: int):
    """Per-axis expressions in ``t`` [s] and ``i`` (1-based spacecraft number) -> (count, len(texts))."""
    return _compiled(tuple(str(x) for x in texts), field)(t, spacecraft_numbers(count))


def spacecraft_numbers(count: int):
    """1-based spacecraft numbers as float64 (the ``i`` of scenario expressions)."""
    return jnp.arange(1, count + 1, dtype=jnp.float64)
