"""Switching supervisor of a state-varying switched formation (Yang2013 Sec. 3.3, Fig. 2, Theorem 2)."""

from __future__ import annotations

from functools import lru_cache
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from formation_ftc.blocks.supervisors import switching_supervisor as block
from formation_ftc.core.expressions import compile_vector_expression
from formation_ftc.sim.components import FlightInputs, Signal, Supervisor, component, static

__all__ = ["SwitchDecision", "SwitchingSupervisor", "decision_events"]


class SwitchDecision(NamedTuple):
    """The supervisor's decision in force over one step."""

    mode: jax.Array  # index of the mode in force (0-based)
    next_mode: (
        jax.Array
    )  # index of the mode in force from the end of the step (a switch if != mode)
    active: jax.Array  # (N,) 1 for the spacecraft of the mode, 0 for the others
    reconfigure: jax.Array  # (N,) bool: controller reconfiguration requested (decision 2)
    desired_position: jax.Array  # (N, 3) desired relative positions R~^d(t) of the mode [m]


@lru_cache(maxsize=256)
def _desired_fns(table: tuple) -> tuple:
    return tuple(
        tuple(compile_vector_expression(texts, f"modes[{j}].desired") for texts in row)
        for j, row in enumerate(table)
    )


@component
class SwitchingSupervisor(Supervisor):
    """Per-spacecraft supervisors holding the prescribed mode sequence a priori (N_max slots).

    At every step k (t_k = t0 + k dt) it states the mode in force, its members (``active``) and whether
    a switch follows the step; the truth plant executes membership and state variation. When the FDI
    unit's estimate ``{"diagnosed": (N,) bool}`` reports a fault of a spacecraft in the formation, the
    supervisor decides once (:mod:`formation_ftc.blocks.supervisors.switching_supervisor`): tolerate by
    switching iff the spacecraft leaves at the next switch and (29) holds, else request reconfiguration.
    Decisions, their times, modes and (29) margins are recorded signals.

    ``switch_steps`` (n_modes,) first step of every mode; ``active`` (n_modes, N) membership;
    ``leaves_at_next_switch`` (n_modes, N) bool; ``eta`` [1/s]; ``eta1`` (N,) [1/s];
    ``delay_bound_steps`` (N,) a-priori bound of the diagnosis delay [steps]; ``desired_position``
    per mode and slot three expressions of t [s] and i (the desired relative positions R~^d [m], which
    only enter the drift that the laws cancel: recorded, not used by the laws).
    """

    count: int = static()
    switch_steps: Any = None
    active: Any = None
    leaves_at_next_switch: Any = None
    eta: Any = 0.01
    eta1: Any = 0.01
    delay_bound_steps: Any = 0
    desired_position: tuple = static(default=())

    def initial_state(self):
        n = self.count
        return {
            "decision": jnp.zeros(n, dtype=jnp.int64),
            "decision_time": jnp.full(n, jnp.nan),
            "margin_29": jnp.full(n, jnp.nan),
            "decision_mode": jnp.full(n, -1, dtype=jnp.int64),
        }

    def _desired(self, t, mode):
        i = jnp.arange(1, self.count + 1, dtype=jnp.float64)
        table = jnp.stack(
            [
                jnp.stack([fn(t, i[s]) for s, fn in enumerate(row)])
                for row in _desired_fns(self.desired_position)
            ]
        )  # (n_modes, N, 3)
        return table[mode]

    def _decision(self, k, t, state) -> SwitchDecision:
        mode = block.mode_index(self.switch_steps, k)
        active = self.active[mode]
        return SwitchDecision(
            mode=mode,
            next_mode=block.mode_index(self.switch_steps, k + 1),
            active=active,
            reconfigure=state["decision"] == block.RECONFIGURE,
            desired_position=self._desired(t, mode) * active[:, None],
        )

    def update(self, t, state, inputs: FlightInputs):
        k, dt = inputs.step.k, inputs.step.dt
        mode = block.mode_index(self.switch_steps, k)
        est = inputs.estimate
        diagnosed = jnp.zeros(self.count, dtype=bool) if est is None else est["diagnosed"]
        diagnosed = diagnosed & (self.active[mode] > 0)  # only spacecraft in the formation
        margin, has_next, gain, loss = block.condition_29(
            self.switch_steps, k, self.delay_bound_steps, self.eta, self.eta1, dt
        )  # (29)
        decision, new = block.decide(
            state["decision"], diagnosed, self.leaves_at_next_switch[mode] > 0, has_next, gain, loss
        )
        state = {
            "decision": decision,
            "decision_time": jnp.where(new, t, state["decision_time"]),
            "margin_29": jnp.where(new, margin, state["margin_29"]),
            "decision_mode": jnp.where(new, mode, state["decision_mode"]),
        }
        return state, self._decision(k, t, state)

    def signals(self):
        sc = ("spacecraft",)
        return (
            Signal("mode", (), "1", "active mode sigma(t) (1-based)"),
            Signal("active", sc, "1", "spacecraft in the formation (1) or not (0)"),
            Signal(
                "desired_position",
                ("spacecraft", "axis"),
                "m",
                "desired relative position R~^d",
                "F_i",
            ),
            Signal(
                "supervisor_decision",
                sc,
                "1",
                "supervisor decision: 0 none, 1 tolerate by switching, 2 request controller reconfiguration",
            ),
            Signal(
                "supervisor_decision_time", sc, "s", "time of the supervisor decision (NaN: none)"
            ),
            Signal(
                "supervisor_decision_mode",
                sc,
                "1",
                "mode (1-based) in which the decision was taken (0: none)",
            ),
            Signal(
                "condition_29_margin",
                sc,
                "1",
                "(eta/2) dt1 - (eta1/2) dt2 of (29) at the decision (NaN: none)",
            ),
        )

    def outputs(self, t, state, decision: SwitchDecision):
        return {
            "mode": decision.mode + 1,
            "active": decision.active,
            "desired_position": decision.desired_position,
            "supervisor_decision": state["decision"],
            "supervisor_decision_time": state["decision_time"],
            "supervisor_decision_mode": state["decision_mode"] + 1,
            "condition_29_margin": state["margin_29"],
        }


def decision_events(
    decision, decision_time, decision_mode, margin, dt: float, mode_names=None
) -> list[dict]:
    """Event log of the supervisor decisions from the recorded signals of one sample (the last record
    holds every decision taken up to the horizon): ``supervisor_decision``, ``supervisor_decision_time``
    [s], ``supervisor_decision_mode`` (1-based) and ``condition_29_margin``, each (N,).

    Parameters
    ----------
    decision : array_like, shape (N,)
        Decision code per spacecraft (0: none) [-].
    decision_time : array_like, shape (N,)
        Time of the decision [s].
    decision_mode : array_like, shape (N,)
        Mode in force, 1-based [-].
    margin : array_like, shape (N,)
        Margin of condition (29) at the decision [-].
    dt : float
        Step [s].
    mode_names : sequence of str, optional
        Names of the modes (1-based ``decision_mode`` indexes them).

    Returns
    -------
    list of dict
        One event per decision, by time: time [s], step, spacecraft (1-based), event, decision, mode and
        ``condition_29_margin`` [-].

    Examples
    --------
    >>> from formation_ftc.components.supervisors.switching_supervisor import decision_events
    >>> events = decision_events([0, 1], [0.0, 12.5], [1, 2], [0.0, 0.3], dt=0.5, mode_names=["M1", "M2"])
    >>> events == [{"time": 12.5, "step": 25, "spacecraft": 2, "event": "supervisor decision",
    ...             "decision": "tolerate by switching", "mode": "M2", "condition_29_margin": 0.3}]
    True
    """
    events = []
    for s, code in enumerate(np.asarray(decision).astype(int)):
        if code == block.NO_DECISION:
            continue
        t = float(np.asarray(decision_time)[s])
        mode = int(np.asarray(decision_mode)[s])
        events.append(
            {
                "time": t,
                "step": int(round(t / dt)),
                "spacecraft": s + 1,
                "event": "supervisor decision",
                "decision": block.DECISION_NAMES[int(code)],
                "mode": mode_names[mode - 1] if mode_names else mode,
                "condition_29_margin": float(np.asarray(margin)[s]),
            }
        )
    return sorted(events, key=lambda e: e["time"])
