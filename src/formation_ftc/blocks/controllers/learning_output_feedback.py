"""Learning output-feedback fault-tolerant tracking controller (LOF2TC), Gui et al. 2022 eqs. (30)-(32).

With the tracking error ``e_q = q0 - q`` and ``e_y = C e_q`` (29)::

    pi(t) = G1 pi(t - tau) + G2 e_q^T (K C)^T (K C) e_q                 # (31), uses K C e_q = K e_y
    v(t)  = G3 v(t - tau) + G4 K e_q(t)                                 # (32), K e_q := K e_y (C = I)
    u     = pi(t) K e_y - B^+ E v(t) - B^+ H F_hat(t)                   # (30)

``F_hat`` comes from the iterative learning observer (5). Discrete implementation: the
learning laws are recursions evaluated once per sample with ``tau = m dt`` (m integer >= 1); past
values are read from fixed-size histories (prehistory ``pi(-tau) = pi_init`` [CHOICE, E002-08: so that
pi >= 1/2 initially], ``v(-tau) = v_init``).

Units: e_y in [m, m/s], K in [1/s^2, 1/s], u, v, F_hat in m/s^2 (per unit mass, E002-03), pi [-].

``params``: ``K`` (m, p), ``G1`` scalar [-], ``G2`` scalar [s^4/m^2] (so that pi is dimensionless),
``G3`` (m,) diagonal [-], ``G4`` scalar, ``BpE`` (m, m) = B^+ E, ``BpH`` (m, m) = B^+ H.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import jax.numpy as jnp

from formation_ftc.blocks.observers.iterative_learning_observer import (
    DelayLine,
    delay_init,
    delay_push,
    delay_read,
    matvec,
)

__all__ = ["LofState", "LearningOutputFeedback"]


class LofState(NamedTuple):
    pi_hist: DelayLine  # past learning gains pi_{k-1}, ..., pi_{k-m} [-]
    v_hist: DelayLine  # past compensation terms v_{k-1}, ..., v_{k-m} [m/s^2]


@dataclass(frozen=True)
class LearningOutputFeedback:
    """LOF2TC structure: learning interval in steps (static)."""

    learning_steps: int = 1

    def init(self, pi_prehistory, v_prehistory) -> LofState:
        pi0 = jnp.asarray(pi_prehistory, dtype=jnp.float64)
        v0 = jnp.asarray(v_prehistory, dtype=jnp.float64)
        return LofState(delay_init(pi0, self.learning_steps), delay_init(v0, self.learning_steps))

    def control(self, params: dict, state: LofState, e_y, F_hat):
        """Returns ``(u, pi_k, v_k)`` at the current sample (no state change)."""
        m = self.learning_steps
        Ke = matvec(params["K"], e_y)
        pi = params["G1"] * delay_read(state.pi_hist, m) + params["G2"] * jnp.sum(Ke * Ke)  # (31)
        v = params["G3"] * delay_read(state.v_hist, m) + params["G4"] * Ke  # (32)
        u = pi * Ke - matvec(params["BpE"], v) - matvec(params["BpH"], F_hat)  # (30)
        return u, pi, v

    def update(self, state: LofState, pi, v) -> LofState:
        """Push the current pi_k, v_k into the histories (end of the step)."""
        m = self.learning_steps
        return LofState(delay_push(state.pi_hist, pi, m), delay_push(state.v_hist, v, m))
