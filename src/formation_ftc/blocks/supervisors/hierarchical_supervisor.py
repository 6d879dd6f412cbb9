"""High-level (HL) supervisor of Azizi & Khorasani 2009 (Sec. I-IV; SPEC.md P4.3) as a discrete-event
system: states {Nominal, LLFR-active, FLFR-active}.

Events and guards (evaluated once per control step, branch-free with ``jnp.where`` so the machine runs
inside ``lax.scan`` and under ``vmap``):

* Nominal -> LLFR on "fault estimated": the FDI output (flight side) reports an estimate b_hat_k,
  i.e. ``k >= k_estimated``; the low level then allocates with b_hat (eq. (3)).
* LLFR -> FLFR on "mission bound violated": the *measured* max |e_ij| exceeds e_s for
  ``confirm_steps`` consecutive steps (a dwell counter that rejects single noisy samples), monitoring
  only from ``monitor_start`` on, and only if FLFR is enabled. The formation level then raises the
  weight alpha_k of the partially recovered satellite to the value designed offline by eq. (9)/(11)
  (:mod:`formation_ftc.design.flfr`).

FLFR is absorbing. Every transition is logged into a fixed-size event log held in the state
(step index, from-mode, to-mode), which the method copies into its result (:func:`events`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

__all__ = ["NOMINAL", "LLFR", "FLFR", "MODE_NAMES", "SupervisorState", "HierarchicalSupervisor", "events"]

NOMINAL, LLFR, FLFR = 0, 1, 2
MODE_NAMES = ("Nominal", "LLFR", "FLFR")


class SupervisorState(NamedTuple):
    """mode (int), consecutive-violation counter (int), event log (k, from, to) and its length."""

    mode: jnp.ndarray
    violations: jnp.ndarray
    event_step: jnp.ndarray
    event_from: jnp.ndarray
    event_to: jnp.ndarray
    n_events: jnp.ndarray


@dataclass(frozen=True)
class HierarchicalSupervisor:
    """Static data: capacity of the event log (two transitions are possible; kept as a parameter)."""

    max_events: int = 4

    def init(self) -> SupervisorState:
        z = jnp.asarray(0, jnp.int64)
        neg = -jnp.ones((self.max_events,), jnp.int64)
        return SupervisorState(mode=jnp.asarray(NOMINAL, jnp.int64), violations=z, event_step=neg,
                               event_from=neg, event_to=neg, n_events=z)

    def step(self, state: SupervisorState, k, error_max, *, k_estimated, e_s, confirm_steps,
             monitor_start, flfr_enabled) -> SupervisorState:
        """Advance the machine at step ``k`` given the measured max |e_ij| [m].

        ``k_estimated``, ``confirm_steps``, ``monitor_start`` are step indices (int); ``e_s`` [m];
        ``flfr_enabled`` bool. Returns the new state (its ``mode`` is the mode to use at step k).
        """
        mode = state.mode
        # Nominal -> LLFR: fault estimate available
        to_llfr = (mode == NOMINAL) & (k >= k_estimated)
        mode1 = jnp.where(to_llfr, LLFR, mode)
        # LLFR -> FLFR: sustained violation of the mission bound e_s
        monitoring = (mode == LLFR) & (k >= monitor_start) & flfr_enabled
        violated = monitoring & (error_max > e_s)
        violations = jnp.where(violated, state.violations + 1, 0)
        to_flfr = violated & (violations >= jnp.maximum(confirm_steps, 1))
        mode2 = jnp.where(to_flfr, FLFR, mode1)
        # log: at most one transition per step (monitoring needs LLFR active before this step)
        changed = mode2 != mode
        idx = jnp.minimum(state.n_events, self.max_events - 1)
        ev_k = state.event_step.at[idx].set(jnp.where(changed, k, state.event_step[idx]))
        ev_f = state.event_from.at[idx].set(jnp.where(changed, mode, state.event_from[idx]))
        ev_t = state.event_to.at[idx].set(jnp.where(changed, mode2, state.event_to[idx]))
        n = state.n_events + changed.astype(jnp.int64)
        return SupervisorState(mode=mode2, violations=violations, event_step=ev_k, event_from=ev_f,
                               event_to=ev_t, n_events=n)


def events(state: SupervisorState, dt: float, t0: float = 0.0) -> list[dict]:
    """Decode the event log of one run (numpy side) into dicts with step, time [s], from and to."""
    n = int(np.asarray(state.n_events))
    out = []
    for j in range(min(n, np.asarray(state.event_step).shape[-1])):
        k = int(np.asarray(state.event_step)[j])
        out.append({"step": k, "time": t0 + k * dt,
                    "from": MODE_NAMES[int(np.asarray(state.event_from)[j])],
                    "to": MODE_NAMES[int(np.asarray(state.event_to)[j])]})
    return out
