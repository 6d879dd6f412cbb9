"""Iterative learning observer (ILO) for thruster-fault reconstruction, Gui et al. 2022 eq. (5).

Continuous-time law (5), with e_y = y - C q_hat::

    q_hat_dot = A q_hat + B u + H F_hat + L1 e_y + gamma sgn(e_y)       (sign term: E002-02)
    F_hat(t)  = Q1 F_hat(t - tau) + Q2 L2 e_y(t)                         (learning update)

Discrete implementation: at sample k (t_k = k dt) the learning update is evaluated
first, ``F_hat_k = Q1 F_hat_{k-m} + Q2 L2 e_y,k`` with ``m = tau/dt`` an integer number of steps, the
past estimates read from a fixed-size history (ring buffer, :mod:`formation_ftc.core.history`,
prehistory ``F_hat(t) = F_hat(-tau)`` for t < 0); then ``q_hat`` is propagated by forward Euler with
``e_y``, ``u`` and ``F_hat_k`` held over the step. ``sign_term=False`` gives the earlier ILO of the
paper's ref. [25] (same structure without the robustifying ``gamma sgn`` term).

Units: q in [m, m/s], u, F in m/s^2 (per unit mass, E002-03), L1 [1/s], L2 [1/s] (velocity rows),
gamma [m/s^2], dt and tau [s].

``params`` (a dict of arrays, vmappable): ``A`` (n, n), ``B`` (n, m_u), ``H`` (n, m), ``C`` (p, n)
(omit ``C`` for C = I), ``L1`` (n, p), ``L2`` (m, p), ``Q1`` (m,) diagonal, ``Q2`` scalar, ``gamma`` scalar.
Matrix-vector products are written as broadcast multiply + sum (:func:`matvec`): for 6x6 matrices XLA
fuses them into one loop instead of calling a dot kernel each, which is measurably faster on CPU in a
3-million-step scan (benchmarks/gui2022.py).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import jax.numpy as jnp

from formation_ftc.core.history import History, history_init, history_push, history_read

__all__ = ["IloState", "IterativeLearningObserver", "learning_steps", "LearningIntervalError", "matvec",
           "DelayLine", "delay_init", "delay_read", "delay_push"]


def matvec(M, v):
    """``M @ v`` for small matrices as a fusible broadcast-multiply-sum."""
    return jnp.sum(M * v[..., None, :], axis=-1)


class DelayLine(NamedTuple):
    """Values of the last m samples of a signal for a law that reads x(t - m dt).

    m = 1 keeps just the previous sample (no indexing: the hot path of tau = dt); m > 1 uses the ring
    buffer of :mod:`formation_ftc.core.history`.
    """

    last: jnp.ndarray | None  # m == 1: the previous sample
    ring: History | None  # m > 1


def delay_init(prehistory, m: int) -> DelayLine:
    """Constant prehistory x(t) = prehistory for t < 0."""
    x0 = jnp.asarray(prehistory, dtype=jnp.float64)
    return DelayLine(x0, None) if m == 1 else DelayLine(None, history_init(x0, m))


def delay_read(line: DelayLine, m: int):
    """x_{k-m} (the sample m steps before the current one)."""
    return line.last if m == 1 else history_read(line.ring, m - 1, mode="zoh")


def delay_push(line: DelayLine, value, m: int) -> DelayLine:
    """Append x_k (end of step k)."""
    return DelayLine(value, None) if m == 1 else DelayLine(None, history_push(line.ring, value))


class LearningIntervalError(ValueError):
    """tau is not a positive integer multiple of the step."""


def learning_steps(tau: float, dt: float, field: str = "learning_interval") -> int:
    """``tau / dt`` as an integer >= 1; raises :class:`LearningIntervalError` otherwise (PERFORMANCE.md:
    learning laws with t - tau need tau to be an integer number of steps)."""
    if not (tau > 0 and dt > 0):
        raise LearningIntervalError(f"{field} = {tau} s and simulation.dt = {dt} s must be > 0")
    m = round(tau / dt)
    if m < 1 or abs(m * dt - tau) > 1e-9 * max(tau, dt):
        raise LearningIntervalError(
            f"{field} = {tau:g} s is not an integer multiple of simulation.dt = {dt:g} s "
            f"(tau/dt = {tau / dt:.6g}); the learning law reads F_hat(t - tau) from the step grid, so "
            f"tau must be k*dt with an integer k >= 1")
    return int(m)


class IloState(NamedTuple):
    q_hat: jnp.ndarray  # (n,) state estimate at the current sample [m, m/s]
    F_hist: DelayLine  # past fault estimates F_hat_{k-1}, ..., F_hat_{k-m} [m/s^2]


@dataclass(frozen=True)
class IterativeLearningObserver:
    """Structure of the ILO (static): step ``dt`` [s], learning interval in steps, sign term on/off."""

    dt: float
    learning_steps: int = 1
    sign_term: bool = True

    def init(self, q_hat0, F_hat_prehistory) -> IloState:
        """Initial estimate ``q_hat(0)`` and the constant prehistory ``F_hat(t), t < 0``."""
        F0 = jnp.asarray(F_hat_prehistory, dtype=jnp.float64)
        return IloState(jnp.asarray(q_hat0, dtype=jnp.float64), delay_init(F0, self.learning_steps))

    def learn(self, params: dict, state: IloState, y) -> tuple[jnp.ndarray, jnp.ndarray]:
        """Learning update at the current sample: returns ``(F_hat_k, e_y_k)``.  # Gui2022 eq. (5)"""
        y_hat = matvec(params["C"], state.q_hat) if "C" in params else state.q_hat
        e_y = y - y_hat
        F_past = delay_read(state.F_hist, self.learning_steps)  # F_hat(t - tau)
        F_hat = params["Q1"] * F_past + params["Q2"] * matvec(params["L2"], e_y)
        return F_hat, e_y

    def correction(self, params: dict, e_y) -> jnp.ndarray:
        """Output-injection term ``L1 e_y + gamma sgn(e_y)`` (sgn(0) = 0)."""
        corr = matvec(params["L1"], e_y)
        if self.sign_term:
            corr = corr + params["gamma"] * jnp.sign(e_y)  # E002-02: 6-vector sign term (C = I)
        return corr

    def propagate(self, params: dict, state: IloState, u, F_hat, e_y) -> IloState:
        """Forward-Euler step of q_hat over [t_k, t_k + dt] and push F_hat_k into the history."""
        qh = state.q_hat
        qh_dot = (matvec(params["A"], qh) + matvec(params["B"], u) + matvec(params["H"], F_hat)
                  + self.correction(params, e_y))
        return IloState(qh + self.dt * qh_dot, delay_push(state.F_hist, F_hat, self.learning_steps))
