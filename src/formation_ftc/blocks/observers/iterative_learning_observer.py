"""Iterative learning observer (ILO) for thruster-fault reconstruction, Gui et al. 2022 eq. (5).

Continuous-time law (5), with e_y = y - C q_hat::

    q_hat_dot = A q_hat + B u + H F_hat + L1 e_y + gamma sgn(e_y)       (sign term: E002-02)
    F_hat(t)  = Q1 F_hat(t - tau) + Q2 L2 e_y(t)                         (learning update)

Discrete implementation: at sample k (t_k = k dt) the learning update is evaluated
first, ``F_hat_k = Q1 F_hat_{k-m} + Q2 L2 e_y,k`` (:func:`ilo_learning_update`) with ``m = tau/dt`` an
integer number of steps, the past estimates read from a delay line (:mod:`formation_ftc.core.delay_line`,
prehistory ``F_hat(t) = F_hat(-tau)`` for t < 0); then ``q_hat`` is propagated by forward Euler with
``e_y``, ``u`` and ``F_hat_k`` held over the step (:func:`ilo_propagate`). Without the sign term
(``gamma`` term dropped) this is the earlier ILO of the paper's ref. [25].

Every function acts on the last axis and broadcasts over leading axes (one row per spacecraft).
Units: q in [m, m/s], u, F in m/s^2 (per unit mass, E002-03), L1 [1/s], L2 [1/s] (velocity rows),
gamma [m/s^2], dt and tau [s]. Shapes: A (n, n), B (n, m_u), H (n, m), L1 (n, p), L2 (m, p), Q1 (m,)
diagonal, Q2 and gamma scalars; C = I (y = q).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from formation_ftc.core.linear import matvec

__all__ = [
    "ilo_learning_update",
    "ilo_correction",
    "ilo_propagate",
    "learning_steps",
    "LearningIntervalError",
]


class LearningIntervalError(ValueError):
    """tau is not a positive integer multiple of the step."""


def learning_steps(tau: float, dt: float, field: str = "learning_interval") -> int:
    """``tau / dt`` as an integer >= 1; raises :class:`LearningIntervalError` otherwise (learning laws
    with t - tau need tau to be an integer number of steps)."""
    if not (tau > 0 and dt > 0):
        raise LearningIntervalError(f"{field} = {tau} s and simulation.dt = {dt} s must be > 0")
    m = round(tau / dt)
    if m < 1 or abs(m * dt - tau) > 1e-9 * max(tau, dt):
        raise LearningIntervalError(
            f"{field} = {tau:g} s is not an integer multiple of simulation.dt = {dt:g} s "
            f"(tau/dt = {tau / dt:.6g}); the learning law reads F_hat(t - tau) from the step grid, so "
            f"tau must be k*dt with an integer k >= 1"
        )
    return int(m)


def ilo_learning_update(F_past: jax.Array, e_y: jax.Array, Q1, Q2, L2) -> jax.Array:
    """``F_hat_k = Q1 F_hat_{k-m} + Q2 L2 e_y,k`` [m/s^2]."""
    return Q1 * F_past + Q2 * matvec(L2, e_y)  # (5), learning update


def ilo_correction(e_y: jax.Array, L1, gamma, sign_term: bool) -> jax.Array:
    """Output injection ``L1 e_y + gamma sgn(e_y)`` (sgn(0) = 0) [m/s, m/s^2]."""
    corr = matvec(L1, e_y)
    if sign_term:
        corr = corr + gamma * jnp.sign(e_y)  # E002-02: 6-vector sign term (C = I)
    return corr


def ilo_propagate(
    q_hat: jax.Array,
    u: jax.Array,
    F_hat: jax.Array,
    e_y: jax.Array,
    A,
    B,
    H,
    L1,
    gamma,
    dt: float,
    sign_term: bool,
) -> jax.Array:
    """Forward-Euler step of ``q_hat`` over [t_k, t_k + dt] with u, F_hat_k, e_y,k held [m, m/s]."""
    qh_dot = (
        matvec(A, q_hat)
        + matvec(B, u)
        + matvec(H, F_hat)
        + ilo_correction(e_y, L1, gamma, sign_term)
    )  # (5), observer
    return q_hat + dt * qh_dot
