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
* otherwise **request controller reconfiguration** (decision 2).

Pure, branch-free functions (``jnp.where``) vectorised over the spacecraft slots (each slot uses only
its own fault information and the prescribed schedule), so they run inside ``lax.scan`` and under
``vmap``. The component :class:`formation_ftc.components.supervisors.switching_supervisor.SwitchingSupervisor`
wraps them with the uniform supervisor signature and records the decisions as signals.
"""

from __future__ import annotations

import jax.numpy as jnp

__all__ = [
    "NO_DECISION",
    "TOLERATE_BY_SWITCHING",
    "RECONFIGURE",
    "DECISION_NAMES",
    "mode_index",
    "condition_29",
    "decide",
]

NO_DECISION = 0
TOLERATE_BY_SWITCHING = 1
RECONFIGURE = 2
DECISION_NAMES = {
    NO_DECISION: "none",
    TOLERATE_BY_SWITCHING: "tolerate by switching",
    RECONFIGURE: "request controller reconfiguration",
}


def mode_index(switch_steps, k):
    """Index of the mode active at step k (mode j starts at step ``switch_steps[j]``, increasing,
    ``switch_steps[0] = 0``)."""
    # compare_all: a few modes, one vectorised comparison (no loop inside the time step)
    return jnp.searchsorted(jnp.asarray(switch_steps), k, side="right", method="compare_all") - 1


def condition_29(switch_steps, k, delay_bound_steps, eta, eta1, dt):
    """Margin of (29) and whether a next mode exists, for a fault diagnosed at step k.

    ``t_f = (k - delay_bound) dt`` [s] estimates the fault time; ``eta`` [1/s] is the decay rate of the
    healthy modes and ``eta1`` (N,) [1/s] the growth rate of the faulty dynamics (28). Returns
    ``(margin, has_next, gain, loss)`` with ``margin = (eta/2) dt1 - (eta1/2) dt2`` (-inf in the last
    mode: no switch can remove the faulty spacecraft).
    """
    switch_steps = jnp.asarray(switch_steps)
    n_modes = switch_steps.shape[0]
    mode = mode_index(switch_steps, k)
    t_i = switch_steps[mode] * dt
    has_next = mode + 1 < n_modes
    t_next = jnp.where(has_next, switch_steps[jnp.minimum(mode + 1, n_modes - 1)] * dt, jnp.inf)
    t_f = (k - jnp.asarray(delay_bound_steps)) * dt  # estimated fault time
    gain = 0.5 * eta * (t_f - t_i)
    loss = 0.5 * jnp.asarray(eta1) * (t_next - t_f)
    margin = jnp.where(has_next, gain - loss, -jnp.inf)  # Yang2013 eq. (29)
    return margin, has_next, gain, loss


def decide(decision, diagnosed, leaves_next, has_next, gain, loss):
    """New decision codes (N,): a newly diagnosed slot without a decision is tolerated by switching iff
    it leaves at the next switch and (29) holds, else reconfiguration is requested; decided once."""
    # (29) is ">= 0": accept the boundary case up to float round-off of the two products
    tolerable = leaves_next & has_next & (gain - loss >= -1e-12 * (jnp.abs(gain) + jnp.abs(loss)))
    new = jnp.asarray(diagnosed) & (decision == NO_DECISION)
    return jnp.where(new, jnp.where(tolerable, TOLERATE_BY_SWITCHING, RECONFIGURE), decision), new
