"""Fixed-step integrators (pure JAX functions).

* :func:`rk4_step` -- classical 4th-order Runge-Kutta on an arbitrary pytree state. A controller that
  is called inside ``rhs`` is evaluated at every RK stage (continuous-time laws, e.g. Li2020); a
  controller computed before the call and passed through ``args`` is held over the step
  (sampled-data, zero-order hold).
* :func:`euler_step` -- forward Euler (used by discrete-time observers, Gui2022).
* :func:`zoh_discretize` -- exact zero-order-hold discretisation of an LTI plant with the matrix
  exponential of the augmented matrix [[A, B], [0, 0]] (Van Loan); :func:`zoh_discretize_jax` is the
  same in JAX (traceable in A and B, e.g. inside a compiled run whose mean motion is a parameter).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

__all__ = [
    "rk4_step",
    "rk4_step_staged",
    "rk4_autonomous_stages",
    "euler_step",
    "zoh_discretize",
    "zoh_discretize_jax",
]

PyTree = Any


def _axpy(a, x, y):
    """y + a*x on pytrees."""
    return jax.tree_util.tree_map(lambda xi, yi: yi + a * xi, x, y)


def _rk4_combine(x, dt, k1, k2, k3, k4):
    """x + dt/6 (k1 + 2 k2 + 2 k3 + k4) on pytrees."""
    return jax.tree_util.tree_map(
        lambda xi, a, b, c, d: xi + (dt / 6.0) * (a + 2.0 * b + 2.0 * c + d), x, k1, k2, k3, k4
    )


def rk4_step(rhs: Callable[..., PyTree], t, x: PyTree, dt, *args) -> PyTree:
    """One RK4 step of ``dx/dt = rhs(t, x, *args)`` from ``t`` to ``t + dt``."""
    # :func:`rk4_step_staged` with no stage input (the same operations)
    return rk4_step_staged(lambda s, y, _, *a: rhs(s, y, *a), t, x, dt, (None,) * 4, *args)


def rk4_step_staged(rhs: Callable[..., PyTree], t, x: PyTree, dt, stage_inputs, *args) -> PyTree:
    """RK4 step of ``dx/dt = rhs(t, x, u(t), *args)`` with inputs precomputed per stage.

    ``stage_inputs`` is ``(u(t), u(t + dt/2), u(t + dt))`` for time-only inputs (the middle value is
    used by stages 2 and 3) or one input per stage ``(u1, u2, u3, u4)`` (e.g. with the stage values of
    a decoupled sub-state from :func:`rk4_autonomous_stages`). Same result as :func:`rk4_step` with
    ``u`` evaluated inside ``rhs``, but the inputs are selected statically (no run-time selection)
    and each is evaluated once.
    """
    if len(stage_inputs) == 3:
        u0, u_half, u1 = stage_inputs
        stage_inputs = (u0, u_half, u_half, u1)
    if len(stage_inputs) != 4:
        raise ValueError(
            f"rk4_step_staged: stage_inputs must hold 3 or 4 values, got {len(stage_inputs)}"
        )
    ua, ub, uc, ud = stage_inputs
    k1 = rhs(t, x, ua, *args)
    k2 = rhs(t + 0.5 * dt, _axpy(0.5 * dt, k1, x), ub, *args)
    k3 = rhs(t + 0.5 * dt, _axpy(0.5 * dt, k2, x), uc, *args)
    k4 = rhs(t + dt, _axpy(dt, k3, x), ud, *args)
    return _rk4_combine(x, dt, k1, k2, k3, k4)


def rk4_autonomous_stages(f: Callable[[PyTree], PyTree], y: PyTree, dt) -> tuple[PyTree, tuple]:
    """RK4 step of an autonomous sub-system ``dy/dt = f(y)`` that nothing else feeds back into
    (e.g. the reference orbit's true anomaly), run ahead of the main step.

    Returns ``(y(t + dt), (y1, y2, y3, y4))`` where ``y1..y4`` are the states at which RK4 evaluates
    ``f``; the same floating-point operations as integrating ``y`` together with the coupled state, so
    the coupled system can be stepped with :func:`rk4_step_staged` using values computed from
    ``y1..y4`` as its stage inputs (computed once per step, shared by every run of a batch).
    """
    y1 = y
    k1 = f(y1)
    y2 = _axpy(0.5 * dt, k1, y)
    k2 = f(y2)
    y3 = _axpy(0.5 * dt, k2, y)
    k3 = f(y3)
    y4 = _axpy(dt, k3, y)
    k4 = f(y4)
    return _rk4_combine(y, dt, k1, k2, k3, k4), (y1, y2, y3, y4)


def euler_step(rhs: Callable[..., PyTree], t, x: PyTree, dt, *args) -> PyTree:
    """One forward-Euler step."""
    return _axpy(dt, rhs(t, x, *args), x)


def zoh_discretize(A, B, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact ZOH discretisation: returns (Ad, Bd) with Ad = e^{A dt}, Bd = int_0^dt e^{A s} ds B."""
    import scipy.linalg  # on first use: 0.15 s of every simulating command's start otherwise

    A, B = np.asarray(A, dtype=float), np.asarray(B, dtype=float)
    n, m = A.shape[0], B.shape[1]
    E = scipy.linalg.expm(np.block([[A, B], [np.zeros((m, n + m))]]) * dt)
    return E[:n, :n], E[:n, n:]


def zoh_discretize_jax(A, B, dt: float) -> tuple[jax.Array, jax.Array]:
    """:func:`zoh_discretize` in JAX: (Ad, Bd) from expm of [[A, B], [0, 0]] dt (Van Loan)."""
    n, m = A.shape[0], B.shape[1]
    E = jax.scipy.linalg.expm(jnp.block([[A, B], [jnp.zeros((m, n + m))]]) * dt)
    return E[:n, :n], E[:n, n:]
