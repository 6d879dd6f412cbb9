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
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Sequence
from typing import Any

import jax
import numpy as np

from formation_ftc.sim import xla
from formation_ftc.sim.cache import lru_get, lru_put

__all__ = ["stack_params", "batched_run", "clear"]

#: batch programs kept per process (least recently used dropped first): a campaign reuses one per
#: structural group and chunk size, and an unbounded cache made a long session hold every executable
MAX_KEPT = 16
_CACHE: OrderedDict[Any, Callable] = OrderedDict()


def stack_params(params: Sequence[Any], size: int | None = None) -> tuple[Any, Any]:
    """Batch a list of ``params`` pytrees (one per run, same structure) for :func:`batched_run`.

    Returns ``(batch, in_axes)``: a leaf that differs between the runs is stacked along a new axis 0
    and padded to ``size`` runs (default: ``len(params)``) with the last run's value, so that every
    chunk of a campaign uses the same program; a leaf equal (same shape, same values, NaN equal to
    NaN) in every run is kept once and its ``in_axes`` entry is None.
    """
    if not params:
        raise ValueError("stack_params: no runs")
    size = len(params) if size is None else int(size)
    if size < len(params):
        raise ValueError(f"stack_params: size = {size} < number of runs {len(params)}")
    flat = [jax.tree_util.tree_flatten(p) for p in params]
    treedef: Any = flat[0][1]  # jax's PyTreeDef is not resolvable from its stubs
    for k, (_, td) in enumerate(flat[1:], start=1):
        if td != treedef:
            raise ValueError(f"stack_params: run {k} has a different parameter structure than run 0")
    leaves: list[np.ndarray] = []
    axes: list[int | None] = []
    for vals in zip(*(f[0] for f in flat), strict=True):
        arrs = [np.asarray(v) for v in vals]
        first = arrs[0]
        shared = all(a.shape == first.shape and np.array_equal(a, first, equal_nan=first.dtype.kind in "fc")
                     for a in arrs[1:])
        if shared:
            leaves.append(first)
            axes.append(None)
        else:
            arrs += [arrs[-1]] * (size - len(arrs))
            leaves.append(np.stack(arrs))
            axes.append(0)
    return jax.tree_util.tree_unflatten(treedef, leaves), jax.tree_util.tree_unflatten(treedef, axes)


def batched_run(compiled, in_axes: Any, size: int) -> Callable[[Any], dict]:
    """``jax.jit(jax.vmap(compiled.run))`` for a batch of ``size`` runs with ``in_axes`` from
    :func:`stack_params`; every output has the run axis first (shared results are broadcast).
    Cached per ``(compiled.static_key, batched leaves, size)``, the :data:`MAX_KEPT` most recently used.
    Compiled with :func:`formation_ftc.sim.xla.compiler_options` (the fast-compile preset when the loop's
    controller sets ``batch_fast_compile``)."""
    flags = tuple(a is not None for a in jax.tree_util.tree_leaves(in_axes, is_leaf=lambda a: a is None))
    key = (compiled.static_key, flags, int(size))
    fn = lru_get(_CACHE, key)
    if fn is None:
        run = compiled.run
        controller = getattr(getattr(compiled, "params", None), "controller", None)  # a ClosedLoop's law
        fast = bool(getattr(controller, "batch_fast_compile", False))
        batch = jax.vmap(lambda p: dict(run(p)), in_axes=(in_axes,), axis_size=int(size))
        fn = lru_put(_CACHE, key, xla.jit(batch, fast_compile=fast), MAX_KEPT)
    return fn


def clear() -> None:
    """Forget the cached batch programs (a long-lived process releases their executables once JAX's own
    caches are cleared too, ``jax.clear_caches()``)."""
    _CACHE.clear()
