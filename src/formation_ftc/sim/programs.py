"""One compiled program per structure, shared by every run of a process.

A scenario builds a :class:`~formation_ftc.sim.loop.ClosedLoop` whose ``static_key`` names its
structure (components, static fields, leaf shapes); its numbers -- gains, masses, fault data, initial
states, seeds -- are its leaves. Two scenarios with equal keys therefore run the same
program. :func:`jitted_run` keeps one ``jax.jit`` of ``run`` per key, so the second run of a structure
in a process -- the same scenario again, or another gain, fault or seed -- is neither traced, lowered
nor compiled again (JAX's in-memory caches hang off the ``jax.jit`` object); a fresh ``jax.jit`` per
run traced and lowered the loop each time (0.3-0.6 s for a closed loop) and then compiled it or loaded
it from the persistent cache. The program is the same, so the results are bit for bit those of a
fresh ``jax.jit``.

Every front end runs through it: :func:`formation_ftc.api.simulate_with_metrics`, ``formation-ftc run``
and the paper reproductions (:mod:`formation_ftc.papers.programs`). At most :data:`MAX_KEPT` programs
are kept (least recently used dropped first), so a long session does not hold every executable it
ever compiled (:mod:`formation_ftc.sim.runtime.lru`).
"""

from __future__ import annotations

import time
from typing import Any

import jax
import numpy as np

from formation_ftc.sim.runtime import xla
from formation_ftc.sim.runtime.lru import LRUCache, kept

__all__ = ["jitted_run", "executable", "clear", "MAX_KEPT"]

#: at most this many programs (and executables) are kept, least recently used dropped first, so that a
#: long session (a notebook, a test run) does not hold every executable it ever compiled
MAX_KEPT = 8
_PROGRAMS: LRUCache = LRUCache(maxsize=MAX_KEPT)
_EXECUTABLES: LRUCache = LRUCache(maxsize=MAX_KEPT)


def _run(loop: Any) -> Any:
    """``loop.run()``: the function every shared program jits."""
    return loop.run()


def jitted_run(loop) -> Any:
    """``jax.jit(ClosedLoop.run)`` compiled with :func:`formation_ftc.sim.runtime.xla.compiler_options`,
    shared by every loop with the same ``static_key`` (JAX still retraces if the leaves' shapes or
    static fields differ).

    Parameters
    ----------
    loop : ClosedLoop
        A loop (:func:`formation_ftc.api.build_loop`).

    Returns
    -------
    jax.stages.Wrapped
        Called with the loop (or another of its structure); returns the run's
        :data:`~formation_ftc.sim.engine.RunOutput`.

    Examples
    --------
    Free drift for 20 s from 100 m radial (compiles the loop once, about a second):

    >>> import numpy as np
    >>> from formation_ftc.components.controllers.none import ZeroController
    >>> from formation_ftc.components.plants.clohessy_wiltshire import ClohessyWiltshirePlant
    >>> from formation_ftc.sim.loop import ClosedLoop
    >>> plant = ClohessyWiltshirePlant(mean_motion=np.float64(1e-3), mass=np.array([10.0]),
    ...                                initial_state_lvlh=np.array([[100.0, 0.0, 0.0, 0.0, 0.0, 0.0]]))
    >>> loop = ClosedLoop(plant=plant, controller=ZeroController(count=1), dt=10.0, n_steps=2)
    >>> from formation_ftc.sim.programs import jitted_run
    >>> fn = jitted_run(loop)
    >>> fn is jitted_run(loop.validate())  # shared by every loop of this structure
    True
    >>> out = fn(loop)
    >>> np.round(np.asarray(out["records"]["position"])[:, 0, 0], 3)  # radial position [m]
    array([100.   , 100.015, 100.06 ])
    """
    return kept(_PROGRAMS, loop.static_key, lambda: xla.jit(_run))


def executable(loop) -> tuple[Any, float]:
    """Ahead-of-time compiled ``ClosedLoop.run`` (``jax.jit(...).lower(loop).compile()``) and the seconds
    [s] that compiling it took here (0.0 when a scenario of the same structure and parameter shapes
    compiled it before; the :data:`MAX_KEPT` most recently used executables are kept).

    Parameters
    ----------
    loop : ClosedLoop
        A loop (:func:`formation_ftc.api.build_loop`).

    Returns
    -------
    executable : jax.stages.Compiled
        Called with the loop (or another of its structure and leaf shapes).
    seconds : float
        Time spent compiling it [s] (0.0 when it was kept).

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.controllers.none import ZeroController
    >>> from formation_ftc.components.plants.clohessy_wiltshire import ClohessyWiltshirePlant
    >>> from formation_ftc.sim.loop import ClosedLoop
    >>> plant = ClohessyWiltshirePlant(mean_motion=np.float64(1e-3), mass=np.array([10.0]),
    ...                                initial_state_lvlh=np.array([[100.0, 0.0, 0.0, 0.0, 0.0, 0.0]]))
    >>> loop = ClosedLoop(plant=plant, controller=ZeroController(count=1), dt=10.0, n_steps=2)
    >>> from formation_ftc.sim.programs import executable
    >>> exe, seconds = executable(loop)
    >>> int(exe(loop)["diverged_step"])
    -1
    >>> executable(loop)[1]  # kept: nothing to do the second time
    0.0
    """
    leaves, treedef = jax.tree_util.tree_flatten(loop)
    kinds = tuple((type(x).__name__, np.shape(x), str(getattr(x, "dtype", ""))) for x in leaves)
    key = (loop.static_key, treedef, kinds)  # kinds: each leaf's type, shape and dtype
    t0 = time.perf_counter()
    built = []

    def build():
        built.append(True)
        return jitted_run(loop).lower(loop).compile()

    exe = kept(_EXECUTABLES, key, build)
    return exe, time.perf_counter() - t0 if built else 0.0


def clear() -> None:
    """Forget the shared programs and release the executables kept by :func:`executable` (out of
    ``jax.clear_caches()``'s reach; JAX's own caches are untouched). A long-lived
    process that wants its memory back calls this, :func:`formation_ftc.sim.batch.clear` and
    ``jax.clear_caches()``.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.controllers.none import ZeroController
    >>> from formation_ftc.components.plants.clohessy_wiltshire import ClohessyWiltshirePlant
    >>> from formation_ftc.sim.loop import ClosedLoop
    >>> plant = ClohessyWiltshirePlant(mean_motion=np.float64(1e-3), mass=np.array([10.0]),
    ...                                initial_state_lvlh=np.array([[100.0, 0.0, 0.0, 0.0, 0.0, 0.0]]))
    >>> loop = ClosedLoop(plant=plant, controller=ZeroController(count=1), dt=10.0, n_steps=2)
    >>> from formation_ftc.sim.programs import clear, jitted_run
    >>> fn = jitted_run(loop)
    >>> clear()
    >>> jitted_run(loop) is fn  # a new program (compiled again on its first call)
    False
    """
    _PROGRAMS.clear()
    _EXECUTABLES.clear()
