"""Scalar time functions shared by the papers. Pure jax.numpy, time t in seconds."""

from __future__ import annotations

import jax.numpy as jnp

__all__ = ["step", "window", "exp_recovery_loe", "sinusoid", "smooth_transition"]


def step(t, t0, a=1.0):
    """0 for t < t0, a for t >= t0."""
    return jnp.where(t >= t0, a, 0.0)


def window(t, t0, t1, value):
    """``value`` on t0 <= t <= t1, else 0."""
    return jnp.where((t >= t0) & (t <= t1), value, 0.0)


def exp_recovery_loe(t, t0, a, r):
    """Effectiveness 1 for t < t0, 1 - a exp(-r (t - t0)) afterwards (jump to 1-a, recovery to 1)."""
    return jnp.where(t >= t0, 1.0 - a * jnp.exp(-r * jnp.maximum(t - t0, 0.0)), 1.0)


def sinusoid(t, amplitude, omega, phase=0.0, bias=0.0):
    """bias + A sin(omega t + phase)."""
    return bias + amplitude * jnp.sin(omega * t + phase)


def smooth_transition(t, chi):
    """g(t) = 1 - exp(-t^2 / (2 chi)) and its first two derivatives (Li2020 Sec. IV-A).

    Returns (g, g_dot, g_ddot); chi in s^2.
    """
    ex = jnp.exp(-(t**2) / (2.0 * chi))
    return 1.0 - ex, (t / chi) * ex, (1.0 / chi - t**2 / chi**2) * ex
