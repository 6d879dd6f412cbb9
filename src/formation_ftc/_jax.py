"""JAX configuration shared by the whole package: float64.

float64 is mandatory: at 7,000 km the float32 spacing is 0.5 m and the gravity terms of the relative
dynamics cancel from about 8 m/s^2 to 1e-3 m/s^2 (measured; docs/performance.md). Importing
:mod:`formation_ftc` switches ``jax_enable_x64`` on before any array is created; nothing else. The
persistent compilation cache and the compiler tuning are :func:`formation_ftc.sim.runtime.configure`'s
(applied here to an already imported JAX when this process is configured).
"""

from __future__ import annotations

import jax

jax.config.update("jax_enable_x64", True)

from formation_ftc.sim import runtime  # noqa: E402

if runtime.configured():
    runtime.configure()

__all__ = ["jax"]
