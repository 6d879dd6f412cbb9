"""XLA:CPU compile options for the simulation programs, and the one ``jit`` that applies them.

A closed-loop run is a long ``lax.scan`` of a step made of many tiny array operations (a few spacecraft,
3-vectors, 3 x 3 matrices). On the CPU such a step costs what XLA's runtime spends dispatching its
operations more than the arithmetic. Three compile options change that cost (measured on the 2-core
machine, best of 3-5 alternating repeats; docs/performance.md):

* **YNNPACK library fusions off** (``xla_cpu_experimental_ynn_fusion_type`` empty), on every program:
  XLA's default hands element-wise groups to a library call whose fixed cost is far above the work on a
  60 x 8 x 3 array; with it off XLA emits its own loops. Mehrabian seed study (60 runs x 8 spacecraft):
  21-23 -> 15-16 us per run-step; Li2020 ``reproduce`` run phase 16.4 -> 14.8 s; single Gui2022 observer
  runs unchanged (1.8 us per step).
* **XLA's own loop emitter instead of its MLIR fusion emitters** (``xla_cpu_use_fusion_emitters`` off),
  on every program: XLA:CPU compiles every fusion of the program through an MLIR pipeline of its own,
  about 12 ms per fusion, and a closed-loop step has 150-200 fusions; its older emitter writes the same
  loops straight into LLVM IR. Compile time of ``formation-ftc run`` per built-in scenario: li2020-thm1
  3.5 -> 2.4 s, gui2022-lof2tc 2.9 -> 1.3 s, azizi2009-llfr 1.4 -> 0.8 s, the Mehrabian seed study 6.2
  -> 3.8 s. Run time: the Mehrabian seed study 19 -> 8.7 us per run-step (with the preset below),
  li2020-thm1 about 10 % faster, the small Gui2022 and Azizi2009 steps 5-40 % slower (1.5-1.8 ->
  2.0-2.1 us per step; ``reproduce gui2022`` run phase 38-41 -> 42-44 s). Elementwise functions (sin,
  exp, log, tanh, pow, arctan2, ...) give the same bits with either emitter (``tests/sim/runtime/test_xla.py``);
  what differs is the order of some fused reductions, i.e. the last bit of a sum.
* **The fast-compile optimisation preset** (``xla_cpu_opt_preset = CPU_OPT_PRESET_FAST_COMPILE``), on
  batched programs whose controller asks for it (:attr:`~formation_ftc.sim.components.Controller.batch_fast_compile`):
  Mehrabian seed study 15 -> 10.6-11 us per run-step, but it skips XLA's hoisting of small loops, which
  makes small steps slower (single Azizi2009 run 1.7 -> 3.2 us per step, batched Gui2022 observer 0.38
  -> 0.67 us per run-step). Hence opt-in per law, not a default.

No option enables fast-math or reassociation; they change which kernels XLA emits, so a result can
differ from XLA's default build in the last bits. ``reproduce all`` prints the same numbers and verdicts
with and without them; underneath, Mehrabian and Yang2013 values differ by about 1e-15 relative,
Gui2022 by 1e-12, Azizi2009 by 1e-11, and li2020's adaptive loop carries a last-bit difference to 1e-5
relative over 3,000 s (docs/performance.md). The
options go to each compilation (``jax.jit(..., compiler_options=...)``), never to the process-wide
``XLA_FLAGS``: an option this jaxlib does not know is dropped after a one-time probe instead of
aborting the process, and other JAX code in the same process is untouched.
``FORMATION_FTC_XLA_OPTIONS=off`` switches them off (A/B measurements).

**Unrolled threefry on the CPU** (:func:`use_unrolled_threefry`, called by :func:`formation_ftc.sim.runtime.configure`). JAX
lowers its threefry hash on the CPU as a 5-iteration loop (smaller programs); inside a simulation step
each noise draw then runs as a nested loop whose iterations XLA dispatches one by one. The unrolled
lowering -- the one JAX uses on other backends -- does the same integer operations, so the random
numbers are identical bit for bit (``tests/sim/runtime/test_xla.py`` compares them with a process that keeps
the loop). Azizi2009 noisy seed batch (220 runs): 0.82 -> 0.68 us per run-step. It uses JAX's internal
lowering registry; on a JAX without those internals nothing changes.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Callable
from typing import Any

import jax

__all__ = [
    "DEFAULT_OPTIONS",
    "FAST_COMPILE_OPTIONS",
    "compiler_options",
    "jit",
    "ENV_SWITCH",
    "use_unrolled_threefry",
]

#: environment variable that switches the options off (``off``, ``0``, ``false`` or ``no``)
ENV_SWITCH = "FORMATION_FTC_XLA_OPTIONS"

#: options of every simulation program
DEFAULT_OPTIONS: dict[str, str | bool] = {
    "xla_cpu_experimental_ynn_fusion_type": "",
    "xla_cpu_use_fusion_emitters": False,
}
#: options of a batched program whose controller asks for the fast-compile preset
FAST_COMPILE_OPTIONS: dict[str, str | bool] = {
    **DEFAULT_OPTIONS,
    "xla_cpu_opt_preset": "CPU_OPT_PRESET_FAST_COMPILE",
}


def _enabled() -> bool:
    return os.environ.get(ENV_SWITCH, "").strip().lower() not in {"off", "0", "false", "no"}


@functools.cache
def _supported(name: str, value: str | bool) -> bool:
    """Whether this jaxlib's compiler accepts ``name=value`` (compiles a one-operation program once)."""
    try:
        jax.jit(lambda x: x + 1.0).lower(jax.numpy.zeros(1)).compile(compiler_options={name: value})
    except Exception:  # an unknown option or value: INVALID_ARGUMENT from the compiler
        return False
    return True


def compiler_options(fast_compile: bool = False) -> dict[str, str | bool]:
    """:data:`DEFAULT_OPTIONS` (or :data:`FAST_COMPILE_OPTIONS`) that this jaxlib accepts, on the CPU
    backend; empty on other backends or when :data:`ENV_SWITCH` is ``off``.

    Parameters
    ----------
    fast_compile : bool, optional
        Add the fast-compile preset.

    Returns
    -------
    dict
        Option name -> value, for ``jax.jit(..., compiler_options=...)``.

    Examples
    --------
    >>> import os
    >>> from unittest import mock
    >>> from formation_ftc.sim.runtime import xla
    >>> set(xla.compiler_options(fast_compile=True)) <= set(xla.FAST_COMPILE_OPTIONS)
    True
    >>> with mock.patch.dict(os.environ, {xla.ENV_SWITCH: "off"}):
    ...     xla.compiler_options()
    {}
    """
    if not _enabled() or jax.default_backend() != "cpu":
        return {}
    wanted = FAST_COMPILE_OPTIONS if fast_compile else DEFAULT_OPTIONS
    return {k: v for k, v in wanted.items() if _supported(k, v)}


def jit(fn: Callable[..., Any], *, fast_compile: bool = False, **kwargs: Any) -> Callable[..., Any]:
    """``jax.jit(fn, **kwargs)`` compiled with :func:`compiler_options` (and, in a process the runtime is
    configured for, :func:`use_unrolled_threefry` first and the compilation cache checked again,
    :func:`formation_ftc.sim.runtime.check_cache`). Every simulation program is made here.

    Parameters
    ----------
    fn : callable
        The function.
    fast_compile : bool, optional
        Use the fast-compile preset.
    **kwargs
        Further ``jax.jit`` arguments.

    Returns
    -------
    callable
        The jitted function.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.sim.runtime import xla
    >>> np.asarray(xla.jit(lambda x: 2.0 * x)(np.arange(3.0)))
    array([0., 2., 4.])
    """
    from formation_ftc.sim import runtime

    if runtime.configured():
        use_unrolled_threefry()
        runtime.check_cache()
    opts = compiler_options(fast_compile)
    return jax.jit(fn, compiler_options=opts, **kwargs) if opts else jax.jit(fn, **kwargs)


def use_unrolled_threefry() -> bool:
    """Lower ``jax.random``'s threefry hash unrolled on the CPU as well (same integer operations, same
    bits; see the module docstring). Returns True when the lowering is registered, False when switched
    off (:data:`ENV_SWITCH`) or when this JAX lacks the internals it needs.

    Returns
    -------
    bool
        Whether the unrolled lowering is in use.

    Examples
    --------
    >>> from formation_ftc.sim.runtime import xla
    >>> xla.use_unrolled_threefry()  # False where switched off or where JAX's internals differ
    True
    """
    return _enabled() and _register_unrolled_threefry()


@functools.cache
def _register_unrolled_threefry() -> bool:
    try:
        from jax._src.interpreters import mlir
        from jax._src.random import threefry2x32 as threefry

        mlir.register_lowering(
            threefry.threefry2x32_p, threefry._threefry2x32_lowering_rule, platform="cpu"
        )
    except (ImportError, AttributeError, TypeError):  # another JAX layout: keep JAX's own lowering
        return False
    return True
