"""The HL supervisor of Azizi & Khorasani 2009 as a Supervisor component (modes Nominal / LLFR /
FLFR; equations in :mod:`formation_ftc.blocks.supervisors.hierarchical_supervisor`)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import jax.numpy as jnp
import numpy as np

from formation_ftc.blocks.supervisors.hierarchical_supervisor import (
    MODE_NAMES,
    initial_state,
    transition,
)
from formation_ftc.core.polygon_formation import chain_difference, rotating_polygon
from formation_ftc.sim.components import (
    CompositionError,
    FlightInputs,
    Signal,
    Supervisor,
    component,
    static,
)

__all__ = ["HierarchicalSupervisor", "FAULT_INFORMATION", "NEVER"]

#: where the "fault estimated" event comes from (``HierarchicalSupervisor.fault_information``)
FAULT_INFORMATION = ("scripted", "estimator")
#: a step index no run reaches: the event has not happened
NEVER = np.iinfo(np.int64).max


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

    ``fault_information`` says where the "fault estimated" event comes from: ``"scripted"`` (default)
    -- the step ``k_estimated``; ``"estimator"`` -- the first step at which the estimate of the
    estimator in the loop reports ``estimate["detected"]`` (any element true, e.g. the latched alarm of
    :class:`~formation_ftc.components.estimators.residual_fdi.ResidualFdi`); ``k_estimated`` is then
    not read. ``on_board_chain``: the measurement is the (N, 6) relative state (e.g.
    ``lvlh-relative-state`` sensors) and the chain positions are formed on board,
    ``y_ij = rho_{i+1} - rho_i``, instead of being measured directly.
    """

    count: int = static()
    n_axes: int = static()
    side: Any  # [m]
    omega: Any  # [rad/s]
    e_s: Any  # mission error bound [m]
    k_estimated: Any  # step at which the fault estimate reaches the supervisor (int)
    confirm_steps: Any  # consecutive violations needed (int)
    monitor_start: Any  # first monitored step (int)
    flfr_enabled: Any  # bool
    fault_information: str = static(default="scripted")  # "scripted" | "estimator"
    on_board_chain: bool = static(default=False)  # measurement: (N, 6) relative state

    def __post_init__(self) -> None:
        if self.fault_information not in FAULT_INFORMATION:
            raise CompositionError(
                f"supervisor HierarchicalSupervisor: fault_information = {self.fault_information!r}, "
                f"expected one of {', '.join(FAULT_INFORMATION)}"
            )

    def initial_state(self):
        return initial_state()

    def update(self, t, state, inputs: FlightInputs):
        k = inputs.step.k
        rd, _, _ = rotating_polygon(t, self.count, self.n_axes, self.side, self.omega)
        e = self._chain_position(inputs.measurement) - chain_difference(rd)
        new = transition(
            state,
            k,
            jnp.max(jnp.abs(e)),
            self._k_estimated(k, inputs.estimate),
            self.e_s,
            self.confirm_steps,
            self.monitor_start,
            self.flfr_enabled,
            inputs.step.dt,
        )
        return new, new.mode

    def _chain_position(self, measurement):
        """Measured chain relative positions (N-1, axes) [m]."""
        if self.on_board_chain:
            return chain_difference(measurement[:, : self.n_axes])
        return measurement["position"]

    def _k_estimated(self, k, estimate):
        """Step of the "fault estimated" event: the scripted step, or (estimator mode) this step once
        the estimator reports a detection (never before)."""
        if self.fault_information == "scripted":
            return self.k_estimated
        if not isinstance(estimate, Mapping) or "detected" not in estimate:
            if estimate is None:
                got = "no estimate"
            elif isinstance(estimate, Mapping):
                got = f"an estimate without 'detected' (keys: {', '.join(map(str, estimate))})"
            else:
                got = f"an estimate of type {type(estimate).__name__}, not a mapping"
            raise CompositionError(
                "supervisor HierarchicalSupervisor: fault_information = 'estimator' switches to LLFR "
                f"when the estimator reports estimate['detected'], but the loop's estimator gives {got}"
            )
        detected = jnp.any(jnp.asarray(estimate["detected"]))
        return jnp.where(detected, k, NEVER)

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
            "time_in_flfr": state.time_in_flfr,
        }
