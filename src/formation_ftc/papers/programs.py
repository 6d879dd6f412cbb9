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

__all__ = ["simulate", "jitted_run", "executable", "clear"]

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


def clear() -> None:
    """Forget the shared programs (JAX's own caches are untouched)."""
    _PROGRAMS.clear()
    _EXECUTABLES.clear()
