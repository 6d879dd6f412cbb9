"""formation-ftc: fault-tolerant control of spacecraft formations in JAX (float64).

Public entry points::

    import formation_ftc as ftc
    scenario = ftc.load_scenario("li2020-thm1", overrides={"simulation.horizon": 100.0})
    result = ftc.simulate(scenario)        # xarray.Dataset with provenance attributes
    table = ftc.check(scenario)            # theorem / design conditions

float64 is mandatory. Importing :mod:`formation_ftc` does not import JAX (so that the command line
answers ``--help`` at once); it sets ``JAX_ENABLE_X64`` for the JAX that any later import loads, and
when JAX is already imported it switches ``jax_enable_x64`` on directly (see :mod:`formation_ftc._jax`).
That is the only process-wide change an import makes: the compilation caches and compiler tuning are
switched on by :func:`formation_ftc.sim.runtime.configure` (``formation-ftc`` calls it; a script may).
The names below are loaded on first use.
"""

from __future__ import annotations

import os as _os
import sys as _sys
from typing import TYPE_CHECKING


def _package_version() -> str:
    """The version in pyproject.toml (the single source), read from the installed package's metadata."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("formation-ftc")
    except PackageNotFoundError:  # pragma: no cover - a source tree that was never installed
        return "0+unknown"


def _configure_jax_environment() -> None:
    """float64 for the JAX this process imports (now or later) -- the one process-wide setting an import
    makes -- and JAX imported on first use where it is not imported yet (``FORMATION_FTC_LAZY_JAX=off``:
    at once, where a module imports it). The compilation caches and compiler tuning are opt-in (:func:`formation_ftc.sim.runtime.configure`,
    which the command line calls); a process started by a configured one (its environment says so)
    configures itself here."""
    _os.environ["JAX_ENABLE_X64"] = "1"
    if "jax" in _sys.modules:  # JAX came first: its configuration is already read, set it directly
        from formation_ftc import _jax  # noqa: F401
    else:
        if _os.environ.get("FORMATION_FTC_LAZY_JAX", "").strip().lower() not in {"off", "0", "no"}:
            # JAX imported on first use (formation_ftc._lazy_jax): validating a scenario and building
            # its loop, as `show` and most of `check` do, import no JAX
            from formation_ftc import _lazy_jax

            _lazy_jax.install()
        from formation_ftc.sim import runtime

        if runtime.configured():
            runtime.configure()


_configure_jax_environment()

_LAZY = {
    "check": "formation_ftc.api",
    "list_scenarios": "formation_ftc.api",
    "load_scenario": "formation_ftc.api",
    "save_result": "formation_ftc.api",
    "simulate": "formation_ftc.api",
    "simulate_with_metrics": "formation_ftc.api",
    "SimulationDiverged": "formation_ftc.sim.engine",
}

__all__ = [
    "__version__",
    "check",
    "list_scenarios",
    "load_scenario",
    "save_result",
    "simulate",
    "simulate_with_metrics",
    "SimulationDiverged",
]

if TYPE_CHECKING:  # pragma: no cover - for type checkers and IDEs
    __version__: str
    from formation_ftc.api import (
        check,
        list_scenarios,
        load_scenario,
        save_result,
        simulate,
        simulate_with_metrics,
    )
    from formation_ftc.sim.engine import SimulationDiverged


def __getattr__(name: str):
    if name == "__version__":  # importlib.metadata costs ~30 ms: only when asked
        globals()["__version__"] = value = _package_version()
        return value
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'formation_ftc' has no attribute {name!r}")
    import importlib

    importlib.import_module(
        "formation_ftc._jax"
    )  # x64 and cache, also if JAX was imported meanwhile
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY) | {"__version__"})
