"""High-level (HL) supervisor of Azizi & Khorasani 2009 (Sec. I-IV) as a discrete-event system with
the modes {Nominal, LLFR-active, FLFR-active}.

Events and guards, evaluated once per control step k, branch-free (``jnp.where``) so the machine runs
inside ``lax.scan`` and under ``vmap``:

* Nominal -> LLFR on "fault estimated": the fault estimate b_hat has reached the supervisor
  (``k >= k_estimated``); the low level then allocates with b_hat (eq. (3)). The component passes
  either a scripted step or, fed by a fault detector in the loop, the current step once the detector
  has alarmed (``fault_information = "estimator"``).
* LLFR -> FLFR on "mission bound violated": the *measured* max |e_ij| exceeds e_s for
  ``confirm_steps`` consecutive steps (a dwell counter that rejects single noisy samples), monitoring
  only from ``monitor_start`` on and only if FLFR is enabled. The formation level then raises the
  weight alpha_k of the partially recovered satellite to the value designed offline by eq. (9)/(11)
  (:mod:`formation_ftc.design.flfr`).

FLFR is absorbing. The state also counts the mode changes and the steps spent in FLFR (the switch
step counts as the first). The component wrapper with the uniform ``update(t, state, inputs)``
signature is :class:`formation_ftc.components.supervisors.hierarchical.HierarchicalSupervisor`.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

__all__ = ["NOMINAL", "LLFR", "FLFR", "MODE_NAMES", "HlState", "initial_state", "transition"]

NOMINAL, LLFR, FLFR = 0, 1, 2
MODE_NAMES = ("Nominal", "LLFR", "FLFR")


class HlState(NamedTuple):
    """mode (int), consecutive-violation counter, number of mode changes, steps spent in FLFR and
    that time [s]."""

    mode: jax.Array
    violations: jax.Array
    mode_changes: jax.Array
    flfr_steps: jax.Array
    time_in_flfr: jax.Array


def initial_state() -> HlState:
    """Nominal mode, all counters zero."""
    z = jnp.asarray(0, jnp.int64)
    return HlState(
        mode=jnp.asarray(NOMINAL, jnp.int64),
        violations=z,
        mode_changes=z,
        flfr_steps=z,
        time_in_flfr=jnp.asarray(0.0),
    )


def transition(
    state: HlState,
    k,
    error_max,
    k_estimated,
    e_s,
    confirm_steps,
    monitor_start,
    flfr_enabled,
    dt: float,
) -> HlState:
    """The machine at step ``k`` given the measured max |e_ij| [m]; its ``mode`` is the mode of step k.

    ``k_estimated``, ``confirm_steps``, ``monitor_start``: step indices / counts (int); ``e_s`` [m];
    ``flfr_enabled``: bool; ``dt``: the control step [s] (for the time spent in FLFR).
    """
    mode = state.mode
    # Nominal -> LLFR: fault estimate available
    to_llfr = (mode == NOMINAL) & (k >= k_estimated)
    mode1 = jnp.where(to_llfr, LLFR, mode)
    # LLFR -> FLFR: sustained violation of the mission bound e_s (monitoring needs LLFR before step k)
    monitoring = (mode == LLFR) & (k >= monitor_start) & flfr_enabled
    violated = monitoring & (error_max > e_s)
    violations = jnp.where(violated, state.violations + 1, 0)
    to_flfr = violated & (violations >= jnp.maximum(confirm_steps, 1))
    mode2 = jnp.where(to_flfr, FLFR, mode1)
    changes = state.mode_changes + (mode2 != mode).astype(jnp.int64)
    flfr_steps = jnp.where(mode2 == FLFR, state.flfr_steps + 1, 0)
    return HlState(
        mode=mode2,
        violations=violations,
        mode_changes=changes,
        flfr_steps=flfr_steps,
        time_in_flfr=flfr_steps * dt,
    )
