"""Per-axis double integrator with actuator gains (deep-space formation, Azizi & Khorasani 2009).

Model (Azizi2009 Sec. II, x-axis shown; y and z are identical and decoupled)::

    x_i'' = b_i u_i + d_i            i = 1..N, per axis

with position ``r`` [m] and velocity ``v`` [m/s] of shape ``(..., N, n_axes)``, input ``u`` [N per unit
actuator gain], actuator gain ``b`` [-] (``b = 1`` healthy, ``b < 1`` loss of effectiveness) and
disturbance acceleration ``d`` [m/s^2].

* :func:`rhs` -- continuous right-hand side (for :func:`formation_ftc.core.integrators.rk4_step`);
* :func:`zoh_step` -- the exact update over one step when the acceleration ``b u + d`` is held
  constant over ``[t_k, t_k + dt]`` (zero-order hold); RK4 with a held input gives the same numbers
  up to round-off, because the solution is a quadratic polynomial in time;
* :func:`held_acceleration_step` -- the same update for a given held acceleration ``a`` [m/s^2].
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

__all__ = ["DoubleIntegratorState", "acceleration", "rhs", "zoh_step", "held_acceleration_step"]


class DoubleIntegratorState(NamedTuple):
    """Position ``r`` [m] and velocity ``v`` [m/s], each of shape ``(..., N, n_axes)``."""

    r: jnp.ndarray
    v: jnp.ndarray


def acceleration(u, b, d=0.0):
    """Applied acceleration ``b u + d`` [m/s^2] (Azizi2009 Sec. II model), broadcast over (N, axes)."""
    return b * u + d


def rhs(t, state: DoubleIntegratorState, u, b, d=0.0) -> DoubleIntegratorState:
    """d/dt (r, v) = (v, b u + d). ``t`` [s] is unused (time-invariant plant); kept for RK4."""
    del t
    return DoubleIntegratorState(state.v, acceleration(u, b, d))


def zoh_step(state: DoubleIntegratorState, u, b, d, dt) -> DoubleIntegratorState:
    """Exact update over ``dt`` [s] with ``u`` and ``d`` held constant (zero-order hold).

    ``r+ = r + v dt + a dt^2 / 2``, ``v+ = v + a dt`` with ``a = b u + d``.
    """
    return held_acceleration_step(state, acceleration(u, b, d), dt)


def held_acceleration_step(state: DoubleIntegratorState, a, dt) -> DoubleIntegratorState:
    """Exact update over ``dt`` [s] with the acceleration ``a`` [m/s^2] held constant:
    ``r+ = r + v dt + a dt^2 / 2``, ``v+ = v + a dt``."""
    return DoubleIntegratorState(state.r + state.v * dt + 0.5 * a * dt * dt, state.v + a * dt)
