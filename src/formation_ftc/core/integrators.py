"""Fixed-step integrators (pure JAX functions).

* :func:`rk4_step` -- classical 4th-order Runge-Kutta on an arbitrary pytree state. A controller that
  is called inside ``rhs`` is evaluated at every RK stage (continuous-time laws, e.g. Li2020); a
  controller computed before the call and passed through ``args`` is held over the step
  (sampled-data, zero-order hold).
* :func:`euler_step` -- forward Euler (used by discrete-time observers, Gui2022).
* :func:`zoh_discretize` -- exact zero-order-hold discretisation of an LTI plant with the matrix
  exponential of the augmented matrix [[A, B], [0, 0]] (Van Loan).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import jax
import numpy as np
import scipy.linalg

__all__ = ["rk4_step", "rk4_step_staged", "euler_step", "zoh_discretize"]

PyTree = Any


def _axpy(a, x, y):
    """y + a*x on pytrees."""
    return jax.tree_util.tree_map(lambda xi, yi: yi + a * xi, x, y)


def rk4_step(rhs: Callable[..., PyTree], t, x: PyTree, dt, *args) -> PyTree:
    """One RK4 step of ``dx/dt = rhs(t, x, *args)`` from ``t`` to ``t + dt``."""
    k1 = rhs(t, x, *args)
    k2 = rhs(t + 0.5 * dt, _axpy(0.5 * dt, k1, x), *args)
    k3 = rhs(t + 0.5 * dt, _axpy(0.5 * dt, k2, x), *args)
    k4 = rhs(t + dt, _axpy(dt, k3, x), *args)
    return jax.tree_util.tree_map(
        lambda xi, a, b, c, d: xi + (dt / 6.0) * (a + 2.0 * b + 2.0 * c + d), x, k1, k2, k3, k4
    )


def rk4_step_staged(rhs: Callable[..., PyTree], t, x: PyTree, dt, stage_inputs, *args) -> PyTree:
    """RK4 step of ``dx/dt = rhs(t, x, u(t), *args)`` with time-only inputs precomputed at the three
    distinct stage times: ``stage_inputs = (u(t), u(t + dt/2), u(t + dt))``.

    Same result as :func:`rk4_step` with ``u`` evaluated inside ``rhs``, but the stage inputs are
    selected statically (no run-time selection) and ``u(t + dt/2)`` is evaluated once for stages 2-3.
    """
    u0, u_half, u1 = stage_inputs
    k1 = rhs(t, x, u0, *args)
    k2 = rhs(t + 0.5 * dt, _axpy(0.5 * dt, k1, x), u_half, *args)
    k3 = rhs(t + 0.5 * dt, _axpy(0.5 * dt, k2, x), u_half, *args)
    k4 = rhs(t + dt, _axpy(dt, k3, x), u1, *args)
    return jax.tree_util.tree_map(
        lambda xi, a, b, c, d: xi + (dt / 6.0) * (a + 2.0 * b + 2.0 * c + d), x, k1, k2, k3, k4
    )


def euler_step(rhs: Callable[..., PyTree], t, x: PyTree, dt, *args) -> PyTree:
    """One forward-Euler step."""
    return _axpy(dt, rhs(t, x, *args), x)


def zoh_discretize(A, B, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact ZOH discretisation: returns (Ad, Bd) with Ad = e^{A dt}, Bd = int_0^dt e^{A s} ds B."""
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    n, m = A.shape[0], B.shape[1]
    M = np.zeros((n + m, n + m))
    M[:n, :n] = A
    M[:n, n:] = B
    E = scipy.linalg.expm(M * dt)
    return E[:n, :n], E[:n, n:]
