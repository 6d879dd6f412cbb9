"""One compiled program per structure, reused across a reproduction's scenarios.

:func:`formation_ftc.api.simulate_with_metrics` wraps every scenario's ``run`` in a new ``jax.jit``,
so two scenarios of one structure (same ``Compiled.static_key``: only numbers differ) are traced,
lowered and compiled twice. :func:`simulate` keeps one ``jax.jit`` per ``static_key`` instead: the
second scenario of a structure calls the program the first one compiled. The program is the one
``simulate_with_metrics`` compiles, so the results are bit-for-bit the same.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Any

import jax

from formation_ftc.sim import xla
from formation_ftc.sim.cache import lru_get, lru_put

__all__ = ["simulate", "simulate_batched", "jitted_run", "executable", "clear"]

#: at most this many programs (and executables) are kept, least recently used dropped first, so that a
#: long session (a test run) does not hold every executable it ever compiled
MAX_KEPT = 8
_PROGRAMS: OrderedDict[Hashable, Callable[[Any], Any]] = OrderedDict()
_EXECUTABLES: OrderedDict[Hashable, Any] = OrderedDict()


def jitted_run(compiled) -> Callable[[Any], Any]:
    """``jax.jit(compiled.run)``, shared by every compiled scenario with the same ``static_key``
    (JAX still retraces if the parameters' shapes or static fields differ)."""
    fn = lru_get(_PROGRAMS, compiled.static_key)
    if fn is None:
        fn = lru_put(_PROGRAMS, compiled.static_key, xla.jit(compiled.run), MAX_KEPT)
    return fn


def executable(compiled) -> tuple[Any, float]:
    """Ahead-of-time compiled ``compiled.run`` (``jax.jit(...).lower(params).compile()``) and the
    seconds [s] that compiling it took here (0.0 when a scenario of the same structure and parameter
    shapes compiled it before)."""
    import time

    import numpy as np

    leaves, treedef = jax.tree_util.tree_flatten(compiled.params)
    key = (compiled.static_key, treedef,
           tuple((type(x).__name__, np.shape(x), str(getattr(x, "dtype", ""))) for x in leaves))
    exe = lru_get(_EXECUTABLES, key)
    if exe is not None:
        return exe, 0.0
    t0 = time.perf_counter()
    jitted: Any = jitted_run(compiled)  # a jax.jit function (its stubs type it as a plain callable)
    exe = lru_put(_EXECUTABLES, key, jitted.lower(compiled.params).compile(), MAX_KEPT)
    return exe, time.perf_counter() - t0


def simulate(scenario, raise_on_divergence: bool = True) -> tuple[Any, dict[str, float]]:
    """Run one validated scenario: ``(xarray.Dataset, {metric: float})`` as
    :func:`formation_ftc.api.simulate_with_metrics` returns them, through :func:`jitted_run`."""
    from formation_ftc.api import compile_scenario, finish_run

    compiled = compile_scenario(scenario)
    out = jitted_run(compiled)(compiled.params)
    return finish_run(scenario, compiled, out, raise_on_divergence=raise_on_divergence)


def simulate_batched(scenarios: list, compiled: list | None = None,
                     timings: list | None = None) -> list[tuple[Any, dict[str, float]]]:
    """Run scenarios as one ``jax.vmap`` batch per compiled structure (same ``static_key``: only numbers
    differ; :func:`formation_ftc.sim.batch.batched_run`) and return ``[(xarray.Dataset, {metric: float})]``
    in order, as :func:`simulate` returns them one by one (a divergence raises, as there).

    ``compiled``: the scenarios' :class:`~formation_ftc.registry.Compiled` (default: compiled here).
    ``timings``: a list that receives ``(compile_s, run_s)`` of each run's batch [s], in order."""
    import time

    import numpy as np

    from formation_ftc.api import compile_scenario, finish_run
    from formation_ftc.sim.batch import batched_run, stack_params

    compiled = [compile_scenario(s) for s in scenarios] if compiled is None else compiled
    groups: dict[Hashable, list[int]] = {}
    for i, c in enumerate(compiled):
        groups.setdefault(c.static_key, []).append(i)
    results: list[Any] = [None] * len(compiled)
    times: list[Any] = [None] * len(compiled)
    for idx in groups.values():
        batch, in_axes = stack_params([compiled[i].params for i in idx])
        fn: Any = batched_run(compiled[idx[0]], in_axes, len(idx))  # a jax.jit function
        t0 = time.perf_counter()
        exe = fn.lower(batch).compile()
        t1 = time.perf_counter()
        out = jax.tree_util.tree_map(np.asarray, jax.block_until_ready(exe(batch)))
        t2 = time.perf_counter()
        for j, i in enumerate(idx):
            results[i] = finish_run(scenarios[i], compiled[i], jax.tree_util.tree_map(lambda a, j=j: a[j], out))
            times[i] = (t1 - t0, t2 - t1)
    if timings is not None:
        timings.extend(times)
    return results


def clear() -> None:
    """Forget the shared programs (JAX's own caches are untouched)."""
    _PROGRAMS.clear()
    _EXECUTABLES.clear()
