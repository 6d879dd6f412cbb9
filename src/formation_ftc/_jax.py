"""JAX configuration shared by the whole package.

float64 is mandatory: at 7,000 km the float32 spacing is 0.5 m and the gravity terms of the relative
dynamics cancel from about 8 m/s^2 to 1e-3 m/s^2 (measured; see README "Engine"). Importing :mod:`formation_ftc`
switches ``jax_enable_x64`` on before any array is created and enables the persistent compilation
cache so that the command-line tool starts fast on the second call. The cache keeps programs that
compiled for at least ``JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS`` (JAX's own variable; 0.2 s unless
set, :data:`formation_ftc.DEFAULT_CACHE_MIN_COMPILE_S`).
"""

from __future__ import annotations

import os

import jax

jax.config.update("jax_enable_x64", True)

from formation_ftc import (  # noqa: E402
    DEFAULT_CACHE_MIN_COMPILE_S,
    _compilation_cache_dir,
    _private_cache_dir,
)

_cache_dir = _compilation_cache_dir()
if _cache_dir is not None and _private_cache_dir(_cache_dir):
    try:
        jax.config.update("jax_compilation_cache_dir", _cache_dir)
        jax.config.update("jax_persistent_cache_min_compile_time_secs",
                          float(os.environ.get("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS",
                                                         DEFAULT_CACHE_MIN_COMPILE_S)))
    except Exception:  # pragma: no cover - cache is an optimisation only
        pass
else:
    jax.config.update("jax_compilation_cache_dir", None)

# the threefry hash unrolled on the CPU too (identical random numbers; formation_ftc.sim.xla)
from formation_ftc.sim.xla import use_unrolled_threefry  # noqa: E402

use_unrolled_threefry()

__all__ = ["jax"]
