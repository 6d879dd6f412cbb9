"""Batches of runs of one compiled program: ``jax.vmap`` over the parameters that differ.

A Monte Carlo batch usually varies a few parameters (fault profiles, masses, gains, seeds) and shares
the rest (reference orbit, formation geometry, network). :func:`stack_params` stacks only the leaves
that differ between the runs and passes the others once, unbatched (``in_axes=None``); work that
depends only on shared leaves -- the reference orbit, the desired trajectory and the time-varying
gains of Li2020, for instance -- is then traced unbatched and done once per step for the whole batch
instead of once per run (measured on the ``li2020-thm1`` step: about 1.5x the throughput of stacking
every leaf; see ``benchmarks/engine.py``). Results do not depend on which leaves are shared beyond
the last bit (XLA compiles the two programs separately).

:func:`batched_run` returns the jitted ``vmap`` for a given set of batched leaves, cached by the
compiled program's ``static_key``.

**Grids of runs.** A study often crosses two sets of parameters: seeds x gains, say. In one flat batch
every run draws its own measurement noise, although all runs of one seed draw the same numbers.
:func:`stack_params_grid` and :func:`batched_grid_run` lay the runs out on a grid instead (``rows x
columns``) and nest two ``jax.vmap``: a leaf that changes only from row to row (the seed) is batched
by the outer map alone, so the work that depends on it alone -- the noise draws -- is done once per row
and shared by the row's columns. Azizi2009's seed study (20 seeds x 12 weights): 3.3x faster than one
flat batch, metrics bit for bit equal (``benchmarks/grid_batch.py``; ``tests/sim/test_batch.py`` checks
the runs against runs alone and that the draws carry the row count only).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import jax
import numpy as np

from formation_ftc.sim.runtime import xla
from formation_ftc.sim.runtime.lru import LRUCache, kept

__all__ = ["stack_params", "batched_run", "stack_params_grid", "batched_grid_run", "clear"]

#: batch programs kept per process (least recently used dropped first): a campaign reuses one per
#: structural group and chunk size, and an unbounded cache made a long session hold every executable
MAX_KEPT = 16
_CACHE: LRUCache = LRUCache(maxsize=MAX_KEPT)


def stack_params(params: Sequence[Any], size: int | None = None) -> tuple[Any, Any]:
    """Batch a list of ``params`` pytrees (one per run, same structure) for :func:`batched_run`.

    Returns ``(batch, in_axes)``: a leaf that differs between the runs is stacked along a new axis 0
    and padded to ``size`` runs (default: ``len(params)``) with the last run's value, so that every
    chunk of a campaign uses the same program; a leaf equal (same shape, same values, NaN equal to
    NaN) in every run is kept once and its ``in_axes`` entry is None.

    Parameters
    ----------
    params : sequence of pytree
        Parameters of each run (same structure; SI units).
    size : int, optional
        Number of runs of the batch (>= ``len(params)``).

    Returns
    -------
    batch : pytree
        Stacked (axis 0, length ``size``) or shared leaves.
    in_axes : pytree
        0 for a stacked leaf, None for a shared one.

    Raises
    ------
    ValueError
        No runs, ``size`` too small, or runs of different structure.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.sim.batch import stack_params
    >>> runs = [{"gain": np.array([1.0, 2.0]), "mass": 3.0}, {"gain": np.array([1.0, 2.5]), "mass": 3.0}]
    >>> batch, in_axes = stack_params(runs, size=3)
    >>> in_axes
    {'gain': 0, 'mass': None}
    >>> batch["gain"]
    array([[1. , 2. ],
           [1. , 2.5],
           [1. , 2.5]])
    >>> batch["mass"]
    array(3.)
    """
    if not params:
        raise ValueError("stack_params: no runs")
    size = len(params) if size is None else int(size)
    if size < len(params):
        raise ValueError(f"stack_params: size = {size} < number of runs {len(params)}")
    # one row of runs, padded with the last run: a leaf that differs is stacked down the "columns"
    padded = [*params, *[params[-1]] * (size - len(params))]
    batch, _, in_axes = _stack_grid("stack_params", [padded], lambda r, c: str(c))
    return batch, in_axes


def _batched_flags(axes: Any) -> tuple[bool, ...]:
    """Which leaves an ``in_axes`` tree batches (part of a batch program's cache key)."""
    return tuple(
        a is not None for a in jax.tree_util.tree_leaves(axes, is_leaf=lambda a: a is None)
    )


def _one_run(p: Any) -> Any:
    return dict(p.run())


def batched_run(loop, in_axes: Any, size: int) -> Any:
    """``jax.jit(jax.vmap(ClosedLoop.run))`` for a batch of ``size`` runs with ``in_axes`` from
    :func:`stack_params`; every output has the run axis first (shared results are broadcast).
    Cached per ``(loop.static_key, batched leaves, size)``, the :data:`MAX_KEPT` most recently used.
    Compiled with :func:`formation_ftc.sim.runtime.xla.compiler_options` (the fast-compile preset when the loop's
    controller sets ``batch_fast_compile``).

    Parameters
    ----------
    loop : ClosedLoop
        One run of the batch (any pytree with ``static_key`` and a ``run()`` method).
    in_axes : pytree
        From :func:`stack_params`.
    size : int
        Runs per batch.

    Returns
    -------
    jax.stages.Wrapped
        Called with the batch of :func:`stack_params`; outputs with the run axis first.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.sim.batch import batched_run, stack_params
    >>> from formation_ftc.sim.components import component
    >>> @component
    ... class Product:
    ...     gain: object
    ...     mass: object
    ...     static_key = "doc-batched-run"
    ...     def run(self):
    ...         return {"y": self.mass * self.gain}
    >>> runs = [Product(gain=1.0, mass=3.0), Product(gain=2.0, mass=3.0)]
    >>> batch, in_axes = stack_params(runs)
    >>> np.asarray(batched_run(runs[0], in_axes, size=2)(batch)["y"])
    array([3., 6.])
    """
    batched = jax.vmap(_one_run, in_axes=(in_axes,), axis_size=int(size))
    return _kept(loop, (loop.static_key, _batched_flags(in_axes), int(size)), batched)


def _kept(loop, key: tuple, batched: Any) -> Any:
    """The cached batch program ``key``; on a miss, ``batched`` (the batched run) is jitted -- with
    XLA's fast-compile preset when the loop's controller asks for it in batches -- and kept."""
    fast = bool(getattr(getattr(loop, "controller", None), "batch_fast_compile", False))
    return kept(_CACHE, key, lambda: xla.jit(batched, fast_compile=fast))


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal leaves: same shape, same values, NaN equal to NaN."""
    return a.shape == b.shape and np.array_equal(a, b, equal_nan=b.dtype.kind in "fc")


def stack_params_grid(params: Sequence[Sequence[Any]]) -> tuple[Any, Any, Any]:
    """Batch runs laid out on a grid, ``params[r][c]`` (every row as long, every run the same
    structure), for :func:`batched_grid_run`.

    Returns ``(batch, row_axes, column_axes)``. Each leaf is stored by what it depends on:

    * equal in every run: once, unbatched (``None``, ``None``);
    * equal along every row, different between rows (a seed per row): shape ``(rows, ...)``, batched by
      the outer map only (``0``, ``None``);
    * equal down every column, different between columns (a gain per column): ``(columns, ...)``,
      batched by the inner map only (``None``, ``0``);
    * otherwise ``(rows, columns, ...)``, batched by both (``0``, ``0``).

    Parameters
    ----------
    params : sequence of sequence of pytree
        ``params[r][c]``: parameters of the run in row r, column c (SI units).

    Returns
    -------
    batch : pytree
        Leaves stored by what they depend on (see above).
    row_axes : pytree
        0 for the leaves batched by the outer map, else None.
    column_axes : pytree
        0 for the leaves batched by the inner map, else None.

    Raises
    ------
    ValueError
        No runs, rows of different lengths, or runs of different structure.

    Examples
    --------
    >>> from formation_ftc.sim.batch import stack_params_grid
    >>> grid = [[{"offset": x, "gain": g} for g in (1.0, 2.0, 3.0)] for x in (10.0, 20.0)]
    >>> batch, row_axes, column_axes = stack_params_grid(grid)
    >>> row_axes, column_axes
    ({'gain': None, 'offset': 0}, {'gain': 0, 'offset': None})
    >>> batch["offset"], batch["gain"]
    (array([10., 20.]), array([1., 2., 3.]))
    """
    rows = [list(r) for r in params]
    if not rows or not rows[0]:
        raise ValueError("stack_params_grid: no runs")
    n_cols = len(rows[0])
    for r, row in enumerate(rows):
        if len(row) != n_cols:
            raise ValueError(f"stack_params_grid: row {r} has {len(row)} runs, row 0 has {n_cols}")
    return _stack_grid("stack_params_grid", rows, lambda r, c: f"({r}, {c})")


def _stack_grid(fn: str, rows: list, label) -> tuple[Any, Any, Any]:
    """:func:`stack_params_grid` of ``rows`` (equally long, not empty): ValueError naming the first run
    of another structure by ``label(r, c)`` in the messages of ``fn``."""
    runs = {label(r, c): p for r, row in enumerate(rows) for c, p in enumerate(row)}
    flat_defs = [jax.tree_util.tree_flatten(p) for p in runs.values()]
    treedef: Any = flat_defs[0][1]  # jax's PyTreeDef is not resolvable from its stubs
    for name, (_, td) in zip(runs, flat_defs, strict=True):
        if td != treedef:
            raise ValueError(
                f"{fn}: run {name} has a different parameter structure than run {label(0, 0)}"
            )
    cols = len(rows[0])
    stored: list[tuple[np.ndarray, int | None, int | None]] = []  # (leaf, row axis, column axis)
    for runs_j in zip(*(leaves for leaves, _ in flat_defs), strict=True):  # leaf j of every run
        grid = [list(map(np.asarray, runs_j[i : i + cols])) for i in range(0, len(runs_j), cols)]
        along_rows = all(_same(a, g[0]) for g in grid for a in g)  # every row constant
        down_cols = all(_same(a, b) for g in grid for a, b in zip(g, grid[0], strict=True))
        if along_rows and down_cols:
            stored.append((grid[0][0], None, None))
        elif along_rows:  # one value per row
            stored.append((np.stack([g[0] for g in grid]), 0, None))
        elif down_cols:  # one value per column
            stored.append((np.stack(grid[0]), None, 0))
        else:
            stored.append((np.stack([np.stack(g) for g in grid]), 0, 0))
    leaves, row_axes, col_axes = ([s[i] for s in stored] for i in range(3))
    unflat = jax.tree_util.tree_unflatten
    return unflat(treedef, leaves), unflat(treedef, row_axes), unflat(treedef, col_axes)


def batched_grid_run(loop, row_axes: Any, column_axes: Any, rows: int, columns: int) -> Any:
    """``jax.jit(jax.vmap(jax.vmap(ClosedLoop.run)))`` for a ``rows x columns`` grid of runs batched by
    :func:`stack_params_grid`; every output has the run axes ``(rows, columns)`` first. Work that depends
    only on a row's leaves is done once per row. Cached with :func:`batched_run`'s programs.

    Parameters
    ----------
    loop : ClosedLoop
        One run of the grid (any pytree with ``static_key`` and a ``run()`` method).
    row_axes, column_axes : pytree
        From :func:`stack_params_grid`.
    rows, columns : int
        Grid size.

    Returns
    -------
    jax.stages.Wrapped
        Called with the batch of :func:`stack_params_grid`; outputs with the axes ``(rows, columns)``
        first.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.sim.batch import batched_grid_run, stack_params_grid
    >>> from formation_ftc.sim.components import component
    >>> @component
    ... class Sum:
    ...     offset: object
    ...     gain: object
    ...     static_key = "doc-batched-grid-run"
    ...     def run(self):
    ...         return {"y": self.gain + self.offset}
    >>> grid = [[Sum(offset=x, gain=g) for g in (1.0, 2.0, 3.0)] for x in (10.0, 20.0)]
    >>> batch, row_axes, column_axes = stack_params_grid(grid)
    >>> np.asarray(batched_grid_run(grid[0][0], row_axes, column_axes, rows=2, columns=3)(batch)["y"])
    array([[11., 12., 13.],
           [21., 22., 23.]])
    """
    inner = jax.vmap(_one_run, in_axes=(column_axes,), axis_size=int(columns))
    batched = jax.vmap(inner, in_axes=(row_axes,), axis_size=int(rows))
    flags = (_batched_flags(row_axes), _batched_flags(column_axes))
    return _kept(loop, (loop.static_key, "grid", *flags, int(rows), int(columns)), batched)


def clear() -> None:
    """Forget the cached batch programs (their executables go with them once nothing else holds
    them).

    Examples
    --------
    >>> import types
    >>> from formation_ftc.sim.batch import batched_run, clear
    >>> prog = types.SimpleNamespace(static_key="doc-batch-clear", run=lambda p: {"y": 2.0 * p["x"]})
    >>> fn = batched_run(prog, {"x": 0}, 2)
    >>> batched_run(prog, {"x": 0}, 2) is fn  # cached
    True
    >>> clear()
    >>> batched_run(prog, {"x": 0}, 2) is fn  # built again
    False
    """
    _CACHE.clear()
