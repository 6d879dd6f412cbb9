"""The HL supervisor of Azizi & Khorasani 2009 as a Supervisor component (modes Nominal / LLFR /
FLFR; equations in :mod:`formation_ftc.blocks.supervisors.hierarchical_supervisor`)."""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp

from formation_ftc.blocks.supervisors.hierarchical_supervisor import (
    MODE_NAMES,
    initial_state,
    transition,
)
from formation_ftc.core.polygon_formation import chain_difference, rotating_polygon
from formation_ftc.sim.components import FlightInputs, Signal, Supervisor, component, static

__all__ = ["HierarchicalSupervisor"]


@component
class HierarchicalSupervisor(Supervisor):
    """Discrete-event HL supervisor, updated once per control step k (t_k = t0 + k dt):

    * Nominal -> LLFR when the fault estimate has arrived (step ``k_estimated``);
    * LLFR -> FLFR when the measured max |e_ij| (chain relative position errors, from the
      ``"position"`` measurement minus the desired rotating polygon of side ``side`` [m] at ``omega``
      [rad/s]) exceeds ``e_s`` [m] for ``confirm_steps`` consecutive steps, from step
      ``monitor_start`` on, if ``flfr_enabled``.

    Decision: the mode (int). Records ``mode``, ``mode_changes`` and ``time_in_flfr`` [s] (time spent
    in FLFR, the switch step counted as the first step).
    """

    count: int = static()
    n_axes: int = static()
    dt: float = static()  # control step [s]
    side: Any  # [m]
    omega: Any  # [rad/s]
    e_s: Any  # mission error bound [m]
    k_estimated: Any  # step at which the fault estimate reaches the supervisor (int)
    confirm_steps: Any  # consecutive violations needed (int)
    monitor_start: Any  # first monitored step (int)
    flfr_enabled: Any  # bool
    t0: float = static(default=0.0)

    def initial_state(self):
        return initial_state()

    def update(self, t, state, inputs: FlightInputs):
        k = jnp.round((t - self.t0) / self.dt).astype(jnp.int64)
        rd, _, _ = rotating_polygon(t, self.count, self.n_axes, self.side, self.omega)
        e = inputs.measurement["position"] - chain_difference(rd)
        new = transition(
            state,
            k,
            jnp.max(jnp.abs(e)),
            self.k_estimated,
            self.e_s,
            self.confirm_steps,
            self.monitor_start,
            self.flfr_enabled,
        )
        return new, new.mode

    def current(self, state):
        return state.mode

    def signals(self):
        return (
            Signal(
                "mode",
                (),
                "1",
                "HL supervisor mode: " + ", ".join(f"{j} = {m}" for j, m in enumerate(MODE_NAMES)),
            ),
            Signal("mode_changes", (), "1", "number of mode changes so far"),
            Signal(
                "time_in_flfr", (), "s", "time spent in FLFR (the switch step counts as one step)"
            ),
        )

    def outputs(self, t, state, decision):
        return {
            "mode": state.mode,
            "mode_changes": state.mode_changes,
            "time_in_flfr": state.flfr_steps * self.dt,
        }
