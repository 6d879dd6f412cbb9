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
    """Per-axis expressions in ``t`` [s] and ``i`` (1-based spacecraft number) -> (count, len(texts)).

    Parameters
    ----------
    texts : sequence of str
        One expression per axis in ``t`` and ``i``, giving SI values.
    field : str
        Scenario field named in error messages.
    t : float or jax.Array
        Time [s].
    count : int
        Number of spacecraft N.

    Returns
    -------
    jax.Array, shape (count, len(texts))
        The values (SI units of the expressions).

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.expressions import vector_expression
    >>> np.asarray(vector_expression(("0.5 * t", "10 * i", "0"), "doc.example", 2.0, count=2))
    array([[ 1., 10.,  0.],
           [ 1., 20.,  0.]])
    """
    return _compiled(tuple(str(x) for x in texts), field)(t, spacecraft_numbers(count))


def spacecraft_numbers(count: int):
    """1-based spacecraft numbers as float64 (the ``i`` of scenario expressions).

    Parameters
    ----------
    count : int
        Number of spacecraft N.

    Returns
    -------
    jax.Array, shape (count,)
        ``1.0, 2.0, ..., N`` [-].

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.expressions import spacecraft_numbers
    >>> np.asarray(spacecraft_numbers(3))
    array([1., 2., 3.])
    """
    return jnp.arange(1, count + 1, dtype=jnp.float64)
