"""Per-spacecraft discrete-event supervisor of Yang et al. 2013, Sec. 3.3 / Fig. 2 and Theorem 2.

Supervisor i holds, a priori, the prescribed mode sequence and switching times and the individual
controller of every mode. When a fault of spacecraft i is *diagnosed* (flight side: it sees only the
diagnosis, never the true fault), it decides once:

* **tolerate by switching** (decision 1) iff spacecraft i leaves the formation at the next switch --
  departure (Case 1) or docking/merging into the main spacecraft (Case 2), i.e. its state does not
  continue into the next mode -- **and** condition (29) holds,
  ``(eta/2) dt1 - (eta1/2) dt2 >= 0`` with ``dt1 = t_f - t_i``, ``dt2 = t_{i+1} - t_f``, where the
  fault time is estimated as ``t_f = t_diagnosis - delay_bound`` (the diagnosis delay is counted in
  dt2, as the paper requires);
* otherwise **request controller reconfiguration** (decision 2); the loop then uses the
  reconfigured (nominal) gain from that step on.

Branch-free (``jnp.where``) so it runs inside ``lax.scan`` and under ``vmap``; one supervisor per
spacecraft slot, vectorised over the slot axis (each slot uses only its own fault information and the
prescribed schedule). The decision, its step and the (29) margin stay in the state, so the final state
is the event log (:func:`decision_events`).
"""

from __future__ import annotations

from dataclasses import dataclass

import jax.numpy as jnp
import numpy as np

__all__ = [
    "NO_DECISION",
    "TOLERATE_BY_SWITCHING",
    "RECONFIGURE",
    "DECISION_NAMES",
    "SwitchingSupervisor",
    "decision_events",
]

NO_DECISION = 0
TOLERATE_BY_SWITCHING = 1
RECONFIGURE = 2
DECISION_NAMES = {NO_DECISION: "none", TOLERATE_BY_SWITCHING: "tolerate by switching",
                  RECONFIGURE: "request controller reconfiguration"}


@dataclass(frozen=True, eq=False)
class SwitchingSupervisor:
    """Static data of the N_max per-spacecraft supervisors.

    Attributes
    ----------
    switch_steps : (n_modes,) int -- first step of every mode (switch_steps[0] = 0), t = k dt
    leaves_at_next_switch : (n_modes, N) bool -- slot active in mode m whose state does not continue
        into mode m+1 (departure or docking); False in the last mode
    eta : decay rate of the healthy modes [1/s]
    eta1 : (N,) growth rate of the faulty dynamics (28) for each slot [1/s]
    delay_bound_steps : (N,) int -- a-priori bound of the diagnosis delay, in steps
    dt : step [s]
    """

    switch_steps: np.ndarray
    leaves_at_next_switch: np.ndarray
    eta: float
    eta1: np.ndarray
    delay_bound_steps: np.ndarray
    dt: float

    @property
    def n_slots(self) -> int:
        return int(self.leaves_at_next_switch.shape[1])

    def init(self) -> dict:
        """Initial supervisor state (no decision taken)."""
        n = self.n_slots
        return {
            "decision": jnp.zeros(n, dtype=jnp.int64),
            "decision_step": jnp.full(n, -1, dtype=jnp.int64),
            "margin_29": jnp.zeros(n),  # finite (the engine flags non-finite states)
            "decision_mode": jnp.full(n, -1, dtype=jnp.int64),
        }

    def mode_at(self, k):
        """Index of the active mode at step k (modes switch at exact step boundaries)."""
        return jnp.searchsorted(jnp.asarray(self.switch_steps), k, side="right") - 1

    def step(self, state: dict, diagnosed, k) -> tuple[dict, dict]:
        """One supervisor update at step k.

        Parameters
        ----------
        state : supervisor state (see :meth:`init`)
        diagnosed : (N,) bool -- a fault of the slot's spacecraft is diagnosed at or before step k
        k : int step index

        Returns
        -------
        (new_state, outputs) with outputs ``reconfigure`` (N,) bool and ``decision`` (N,) int.
        """
        switch_steps = jnp.asarray(self.switch_steps)
        n_modes = switch_steps.shape[0]
        mode = self.mode_at(k)
        t_i = switch_steps[mode] * self.dt
        has_next = mode + 1 < n_modes
        t_next = jnp.where(has_next, switch_steps[jnp.minimum(mode + 1, n_modes - 1)] * self.dt, jnp.inf)
        t_f = (k - jnp.asarray(self.delay_bound_steps)) * self.dt  # estimated fault time
        dt1 = t_f - t_i
        dt2 = t_next - t_f
        gain = 0.5 * self.eta * dt1
        loss = 0.5 * jnp.asarray(self.eta1) * dt2
        margin = jnp.where(has_next, gain - loss, -jnp.inf)  # Yang2013 eq. (29)
        leaves = jnp.asarray(self.leaves_at_next_switch)[mode]
        # (29) is ">= 0": accept the boundary case up to float round-off of the two products
        tolerable = leaves & has_next & (gain - loss >= -1e-12 * (jnp.abs(gain) + jnp.abs(loss)))
        new = jnp.asarray(diagnosed) & (state["decision"] == NO_DECISION)
        decision = jnp.where(new, jnp.where(tolerable, TOLERATE_BY_SWITCHING, RECONFIGURE), state["decision"])
        out_state = {
            "decision": decision,
            "decision_step": jnp.where(new, k, state["decision_step"]),
            "margin_29": jnp.where(new, margin, state["margin_29"]),
            "decision_mode": jnp.where(new, mode, state["decision_mode"]),
        }
        return out_state, {"reconfigure": decision == RECONFIGURE, "decision": decision}


def decision_events(state: dict, dt: float, spacecraft_ids, mode_names=None) -> list[dict]:
    """Event log (list of dicts) from a final supervisor state (numpy arrays)."""
    events = []
    decision = np.asarray(state["decision"])
    for slot, sc in enumerate(spacecraft_ids):
        if decision[slot] == NO_DECISION:
            continue
        k = int(np.asarray(state["decision_step"])[slot])
        mode = int(np.asarray(state["decision_mode"])[slot])
        events.append({
            "time": k * dt,
            "step": k,
            "spacecraft": int(sc),
            "event": "supervisor decision",
            "decision": DECISION_NAMES[int(decision[slot])],
            "mode": (mode_names[mode] if mode_names else mode + 1),
            "condition_29_margin": float(np.asarray(state["margin_29"])[slot]),
        })
    return events
