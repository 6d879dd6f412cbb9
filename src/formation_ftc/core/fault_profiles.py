"""Fault profiles shared by the truth-side actuator and scripted (synthetic) FDI models.

A profile is a pure function of the integer step index, so a fault window snapped to the step grid
acts on whole steps and the FDI model can read the same profile with a latency in steps.
"""

from __future__ import annotations

import jax.numpy as jnp

from formation_ftc.core.expressions import compile_expression

__all__ = ["windowed_additive_faults"]


def windowed_additive_faults(
    k,
    dt: float,
    windows,
    torques: tuple[str, ...],
    spacecraft: tuple[int, ...],
    channels: tuple[int, ...],
    count: int,
    n_channels: int = 3,
):
    """(count, n_channels) additive faults at step ``k`` (int, may be traced; t = k dt) [command units].

    ``windows`` (n_faults, 2) [s] are snapped to the step grid (``round(window / dt)``, both ends
    inclusive); fault f acts in ``channels[f]`` (0-based) of ``spacecraft[f]`` (0-based) with the
    profile ``torques[f]`` (expression in t, i)."""
    kw = jnp.round(jnp.asarray(windows) / dt).astype(jnp.int64)  # snapped [start, end] steps
    out = jnp.zeros((count, n_channels))
    for f, (text, j, p) in enumerate(zip(torques, spacecraft, channels, strict=True)):
        expr = compile_expression(text, ("t", "i"), field=f"faults[{f}].torque")
        mask = jnp.zeros((count, n_channels)).at[j, p].set(1.0)
        on = (k >= kw[f, 0]) & (k <= kw[f, 1])
        out = out + mask * jnp.where(on, expr(t=k * dt, i=float(j + 1)), 0.0)
    return out
