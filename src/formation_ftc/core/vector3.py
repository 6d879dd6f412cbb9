"""Row-wise operations on 3-vectors (last axis of length 3), written component by component.

``jnp.sum(a * b, axis=-1)`` is a reduction: XLA:CPU gives every reduction its own kernel (one more
pass over the whole ``(runs, N, 3)`` batch). The same quantity written as the sum of the three
components is elementwise and fuses with its producer. Use it where the operand is cheap to
recompute: XLA duplicates an elementwise producer into each of its consumers, so component sums of an
expensive expression used several times can be slower (measured on the Li2020 step: the norms of f
for the delta-v and effort integrals +6 %; the inner products of the adaptive law made the step 7x slower).
Results equal the reductions up to the order of the additions (x + y + z).
"""

from __future__ import annotations

import jax.numpy as jnp

__all__ = ["dot3", "norm3", "sq_norm3", "matrix3"]


def dot3(a, b):
    """a . b over the last axis (length 3): shape (...,)."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def sq_norm3(a):
    """||a||^2 over the last axis (length 3)."""
    return dot3(a, a)


def norm3(a):
    """Euclidean norm ||a|| over the last axis (length 3)."""
    return jnp.sqrt(sq_norm3(a))


def matrix3(rows):
    """Stacked 3x3 matrices (..., 3, 3) from three rows of three (...) arrays each (entry [i][j] of
    ``rows`` becomes element (i, j))."""
    return jnp.stack([jnp.stack(row, -1) for row in rows], -2)
