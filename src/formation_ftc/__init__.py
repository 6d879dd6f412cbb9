"""formation-ftc: fault-tolerant control of spacecraft formations in JAX (float64).

Public entry points::

    import formation_ftc as ftc
    scenario = ftc.load_scenario("li2020-thm1", overrides={"simulation.horizon": 100.0})
    result = ftc.simulate(scenario)        # xarray.Dataset with provenance attributes
    table = ftc.check(scenario)            # theorem / design conditions

float64 is mandatory. Importing :mod:`formation_ftc` does not import JAX (so that the command line
answers ``--help`` at once); it sets ``JAX_ENABLE_X64`` and the persistent compilation cache for the
JAX that any later import loads, and when JAX is already imported it switches ``jax_enable_x64`` on
directly (see :mod:`formation_ftc._jax`). The names below are loaded on first use.
"""

from __future__ import annotations

import os as _os
import sys as _sys
from pathlib import Path as _Path
from typing import TYPE_CHECKING


def _package_version() -> str:
    """The version in pyproject.toml (the single source), read from the installed package's metadata."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("formation-ftc")
    except PackageNotFoundError:  # pragma: no cover - a source tree that was never installed
        return "0+unknown"


def _schedulable_cpus() -> int:
    """CPUs this process may run on (its affinity mask; the CPU count where there is none)."""
    try:
        return len(_os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return _os.cpu_count() or 1


def _cpu_threads() -> int:
    """Threads of JAX's CPU client in this process: ``PJRT_NPROC`` when set (JAX reads it when the client
    starts), else JAX's default, one per CPU this process may run on."""
    value = _os.environ.get("PJRT_NPROC", "").strip()
    if value.isdigit() and int(value) > 0:
        return int(value)
    return _schedulable_cpus()


def _compilation_cache_dir() -> str | None:
    """The persistent compilation cache of this process (None: off).

    ``FORMATION_FTC_JAX_CACHE`` (default ``~/.cache/formation_ftc/jax``; ``off`` disables it), one
    subdirectory per CPU-client thread count: XLA partitions some loops by the thread count when it
    compiles, so a program compiled with 2 threads can round differently from the same program compiled
    with 1, and JAX's cache key does not record the count. Keyed this way, a process never loads a
    program compiled for another thread count (another machine sharing the home directory, or
    ``PJRT_NPROC`` set differently)."""
    cache = _os.environ.get("FORMATION_FTC_JAX_CACHE", str(_Path.home() / ".cache" / "formation_ftc" / "jax"))
    if not cache or cache.lower() == "off":
        return None
    return str(_Path(cache) / f"cpu-threads-{_cpu_threads()}")


_UNSAFE_CACHE_REPORTED: set[str] = set()


def _private_cache_dir(cache: str) -> bool:
    """Create the compilation cache ``cache`` (new directories mode 0700) and check that it and its parent
    are real directories owned by this user and writable by nobody else. A cached executable is machine
    code that JAX runs when it loads it, so a directory that another user could write to is not used
    (the cache is off for this process, with one line on stderr)."""
    import stat

    path = _Path(cache)
    try:
        path.mkdir(mode=0o700, parents=True, exist_ok=True)
        for p in (path.parent, path):
            st = _os.lstat(p)
            if (not stat.S_ISDIR(st.st_mode) or st.st_uid != _os.geteuid()
                    or st.st_mode & (stat.S_IWGRP | stat.S_IWOTH)):
                if cache not in _UNSAFE_CACHE_REPORTED:
                    _UNSAFE_CACHE_REPORTED.add(cache)
                    try:
                        print(f"formation-ftc: compilation cache off: {p} is not a directory owned by this user "
                              "and writable by it alone (set FORMATION_FTC_JAX_CACHE to a directory of your "
                              "own, or to off)", file=_sys.stderr)
                    except (OSError, ValueError):  # a closed or full stderr
                        pass
                return False
    except OSError:  # cannot be created or read: the cache is an optimisation only
        return False
    return True


#: the persistent cache keeps programs that took at least this long [s] to compile (JAX's default is 1 s):
#: every simulation program (0.4-2.6 s) but not the eager operations (< 0.05 s), so that a second
#: ``reproduce all`` loads what the first compiled (warm compile phases 16.4 -> 12.8 s, 1 s -> 0.2 s)
DEFAULT_CACHE_MIN_COMPILE_S = "0.2"


def _configure_jax_environment() -> None:
    """x64 and the compilation cache for the JAX this process imports (now or later)."""
    _os.environ["JAX_ENABLE_X64"] = "1"
    cache = _compilation_cache_dir()
    if cache is not None and _private_cache_dir(cache):
        _os.environ["JAX_COMPILATION_CACHE_DIR"] = cache  # also over one inherited from a parent process
        _os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", DEFAULT_CACHE_MIN_COMPILE_S)
    else:  # off, or not private: also when a parent process passed its cache directory down
        _os.environ.pop("JAX_COMPILATION_CACHE_DIR", None)
    if "jax" in _sys.modules:  # JAX came first: its configuration is already read, set it directly
        from formation_ftc import _jax  # noqa: F401


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
    "__version__", "check", "list_scenarios", "load_scenario", "save_result", "simulate",
    "simulate_with_metrics", "SimulationDiverged",
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

    importlib.import_module("formation_ftc._jax")  # x64 and cache, also if JAX was imported meanwhile
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY) | {"__version__"})
