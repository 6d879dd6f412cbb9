"""Supervisor ``switching``: the per-spacecraft discrete-event supervisors of Yang2013's state-varying
switched formation (Sec. 3.3, Fig. 2, Theorem 2), holding the prescribed mode sequence a priori.

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

The decision functions are pure and branch-free (``jnp.where``), vectorised over the spacecraft slots
(each slot uses only its own fault information and the prescribed schedule), so they run inside
``lax.scan`` and under ``vmap``; :class:`SwitchingSupervisor` wraps them with the uniform supervisor
signature and records the decisions as signals.

The section ``[[supervisor.modes]]`` states the sequence (start, members, variation S_ij (10), new states
X*, desired relative positions) with the design constants of Theorems 1-2 that ``formation-ftc check``
states. Row r of a mode's ``variation`` gives the state of ``members[r]`` as a combination of the
previous mode's member states; the remaining members (``members[n_rows:]``) join with the
``new_states`` (X*). A row of zeros may stand for a departed spacecraft and is then listed as member
``0`` (E001-09). The plan is what the truth executes: the supervisor provides the capability
``switching-plan`` (read by the ``switched-formation`` plant and the ``switch-norms`` evaluation). The
a-priori bound of the diagnosis delay is that of a ``scheduled-diagnosis`` estimator (0 without one).
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any, Literal, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from pydantic import Field, field_validator, model_validator

from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.components._sections import STATE_DIM, ErrorState, Vec3Expr, grid_steps
from formation_ftc.config.base import StrictModel
from formation_ftc.core.expressions import compile_vector_expression
from formation_ftc.sim.components import FlightInputs, Signal, Supervisor, component, static
from formation_ftc.sim.contract import VEC, as_float

__all__ = [
    "NO_DECISION",
    "TOLERATE_BY_SWITCHING",
    "RECONFIGURE",
    "DECISION_NAMES",
    "mode_index",
    "condition_29",
    "decide",
    "SwitchDecision",
    "SwitchingSupervisor",
    "decision_events",
    "SwitchingSupervisorSection",
    "SwitchedStructure",
    "switched_structure",
]


# ------------------------------------------------------------------------------------- equations
NO_DECISION = 0
TOLERATE_BY_SWITCHING = 1
RECONFIGURE = 2
DECISION_NAMES = {
    NO_DECISION: "none",
    TOLERATE_BY_SWITCHING: "tolerate by switching",
    RECONFIGURE: "request controller reconfiguration",
}


def mode_index(switch_steps, k):
    """Index of the mode active at step k.

    Parameters
    ----------
    switch_steps : array_like, shape (n_modes,)
        First step of every mode, increasing, ``switch_steps[0] = 0``.
    k : int or jax.Array
        Step index.

    Returns
    -------
    jax.Array
        The 0-based mode index.

    Examples
    --------
    >>> [int(mode_index([0, 10, 20], k)) for k in (0, 9, 10, 25)]
    [0, 0, 1, 2]
    """
    # compare_all: a few modes, one vectorised comparison (no loop inside the time step)
    return jnp.searchsorted(jnp.asarray(switch_steps), k, side="right", method="compare_all") - 1


def condition_29(switch_steps, k, delay_bound_steps, eta, eta1, dt):
    """Margin of (29) and whether a next mode exists, for a fault diagnosed at step k.

    ``t_f = (k - delay_bound) dt`` estimates the fault time; ``margin = (eta/2) dt1 - (eta1/2) dt2``
    with dt1 = t_f - t_i, dt2 = t_{i+1} - t_f (-inf in the last mode: no switch can remove the faulty
    spacecraft).

    Parameters
    ----------
    switch_steps : array_like, shape (n_modes,)
        First step of every mode.
    k : int or jax.Array
        Step of the diagnosis.
    delay_bound_steps : array_like, shape (N,)
        A-priori bound of the diagnosis delay [steps].
    eta : float
        Decay rate of the healthy modes [1/s].
    eta1 : array_like, shape (N,)
        Growth rate of the faulty dynamics (28) [1/s].
    dt : float
        Step [s].

    Returns
    -------
    tuple of jax.Array
        ``(margin, has_next, gain, loss)``, margin, gain and loss (N,) [-].

    Examples
    --------
    >>> import numpy as np
    >>> m, has_next, gain, loss = condition_29([0, 100], 60, np.zeros(1), 0.01, np.full(1, 0.01), 1.0)
    >>> bool(has_next), np.round(np.asarray(m), 6).tolist()  # 0.005 * 60 - 0.005 * 40
    (True, [0.1])
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
    """New decision codes: a newly diagnosed slot without a decision is tolerated by switching iff it
    leaves at the next switch and (29) holds, else reconfiguration is requested; decided once.

    Parameters
    ----------
    decision : jax.Array, shape (N,)
        Decision codes so far (:data:`NO_DECISION`, ...).
    diagnosed : array_like, shape (N,)
        Diagnosed slots (bool).
    leaves_next : array_like, shape (N,)
        Slots that leave at the next switch (bool).
    has_next : bool or jax.Array
        Whether a next mode exists.
    gain, loss : jax.Array, shape (N,)
        The two terms of (29) (:func:`condition_29`) [-].

    Returns
    -------
    tuple of jax.Array
        The decision codes (N,) and the slots decided now (N,) bool.

    Examples
    --------
    >>> import numpy as np
    >>> codes, new = decide(np.zeros(2, int), np.array([True, True]), np.array([True, False]), True,
    ...                     np.full(2, 0.3), np.full(2, 0.2))
    >>> np.asarray(codes).tolist()  # 1: tolerate by switching, 2: reconfigure
    [1, 2]
    """
    # (29) is ">= 0": accept the boundary case up to float round-off of the two products
    tolerable = leaves_next & has_next & (gain - loss >= -1e-12 * (jnp.abs(gain) + jnp.abs(loss)))
    new = jnp.asarray(diagnosed) & (decision == NO_DECISION)
    return jnp.where(new, jnp.where(tolerable, TOLERATE_BY_SWITCHING, RECONFIGURE), decision), new


# ------------------------------------------------------------------------------------ component
class SwitchDecision(NamedTuple):
    """The supervisor's decision in force over one step."""

    mode: jax.Array  # index of the mode in force (0-based)
    #: index of the mode in force from the end of the step (a switch if != mode)
    next_mode: jax.Array
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
    supervisor decides once (:func:`decide`): tolerate by
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
        mode = mode_index(self.switch_steps, k)
        active = self.active[mode]
        return SwitchDecision(
            mode=mode,
            next_mode=mode_index(self.switch_steps, k + 1),
            active=active,
            reconfigure=state["decision"] == RECONFIGURE,
            desired_position=self._desired(t, mode) * active[:, None],
        )

    def update(self, t, state, inputs: FlightInputs):
        k, dt = inputs.step.k, inputs.step.dt
        mode = mode_index(self.switch_steps, k)
        est = inputs.estimate
        diagnosed = jnp.zeros(self.count, dtype=bool) if est is None else est["diagnosed"]
        diagnosed = diagnosed & (self.active[mode] > 0)  # only spacecraft in the formation
        margin, has_next, gain, loss = condition_29(
            self.switch_steps, k, self.delay_bound_steps, self.eta, self.eta1, dt
        )  # (29)
        decision, new = decide(
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
        codes = ", ".join(f"{code} {name}" for code, name in DECISION_NAMES.items())
        return (
            Signal("mode", (), "1", "active mode sigma(t) (1-based)"),
            Signal("active", sc, "1", "spacecraft in the formation (1) or not (0)"),
            Signal("desired_position", VEC, "m", "desired relative position R~^d", "F_i"),
            Signal("supervisor_decision", sc, "1", f"supervisor decision: {codes}"),
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

    def provides(self) -> frozenset[str]:
        return frozenset({"switching-plan"})


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
    >>> from formation_ftc.components.supervisors.switching import decision_events
    >>> events = decision_events([0, 1], [0.0, 12.5], [1, 2], [0.0, 0.3], dt=0.5, mode_names=["M1", "M2"])
    >>> events == [{"time": 12.5, "step": 25, "spacecraft": 2, "event": "supervisor decision",
    ...             "decision": "tolerate by switching", "mode": "M2", "condition_29_margin": 0.3}]
    True
    """
    events = []
    for s, code in enumerate(np.asarray(decision).astype(int)):
        if code == NO_DECISION:
            continue
        t = float(np.asarray(decision_time)[s])
        mode = int(np.asarray(decision_mode)[s])
        events.append(
            {
                "time": t,
                "step": int(round(t / dt)),
                "spacecraft": s + 1,
                "event": "supervisor decision",
                "decision": DECISION_NAMES[int(code)],
                "mode": mode_names[mode - 1] if mode_names else mode,
                "condition_29_margin": float(np.asarray(margin)[s]),
            }
        )
    return sorted(events, key=lambda e: e["time"])


# -------------------------------------------------------------------------------------- section
class DesiredPosition(StrictModel):
    spacecraft: int = Field(ge=1, description="Spacecraft number [-].")
    position: Vec3Expr = Field(
        description="Desired relative position R~_i^d(t) in F_i; expressions in t [s] [m]."
    )


class ModeSection(StrictModel):
    name: str = Field(description="Mode name, e.g. 'shape 1' or 'transition 1-2'.")
    kind: Literal["shape", "transition"] = Field(
        "shape", description="Fixed shape or varying transition."
    )
    start: float = Field(ge=0, description="Switching time t_k at which the mode starts [s].")
    members: list[int] = Field(
        description="Spacecraft of the mode in state order (0 = zero-row "
        "placeholder of a departed spacecraft, E001-09) [-]."
    )
    variation: list[list[float]] | None = Field(
        None,
        description="Variation matrix S_ij from the previous mode (10), n_rows x n_prev [-]; "
        "omitted = identity (same members).",
    )
    new_states: list[ErrorState] = Field(
        default_factory=list,
        description="New states X* of the spacecraft joining at this switch (10) (truth: the plant "
        "executes it).",
    )
    desired: list[DesiredPosition] = Field(
        default_factory=list, description="Desired relative positions in this mode (default 0)."
    )

    @field_validator("members")
    @classmethod
    def _members_nonempty(cls, v):
        if not any(m > 0 for m in v):
            raise ValueError(
                "modes[].members must contain at least one spacecraft (a mode with no "
                f"spacecraft ends the formation flight, Yang2013 (10)); got {v}"
            )
        real = [m for m in v if m > 0]
        if len(set(real)) != len(real):
            raise ValueError(f"modes[].members lists a spacecraft twice: {v}")
        if any(m < 0 for m in v):
            raise ValueError(
                f"modes[].members must be spacecraft numbers >= 1 (or 0 placeholders), got {v}"
            )
        return v


class SwitchingSupervisorSection(StrictModel):
    """Prescribed mode sequence and the design constants of Yang2013 Theorems 1-2 (Sec. 3)."""

    modes: list[ModeSection] = builder_input(
        min_length=1, description="Mode sequence in switching order."
    )
    eta: float = Field(0.01, gt=0, description="Decay rate eta of the healthy modes (20) [1/s].")
    eta1: float = Field(
        0.01, ge=0, description="Growth rate eta1 of the faulty dynamics (28) [1/s]."
    )
    zeta: float = builder_input(5.0, gt=0, description="zeta = max_j sqrt(n_j eps) of (20) [-].")
    epsilon: float = builder_input(0.9, gt=0, description="epsilon of Theorem 1 [-].")
    epsilon1: float = builder_input(0.2, gt=0, description="epsilon_1 of (21) [-].")
    epsilon2: float = builder_input(0.4, ge=0, description="epsilon_2 of (22) [-].")
    dwell_time: float = builder_input(80.0, ge=0, description="Dwell time tau of (21) [s].")
    variation_norm: Literal["frobenius", "induced2"] = builder_input(
        "frobenius",
        description="Norm used for S = max|S_ij|: 'frobenius' (paper, sqrt 5) or "
        "'induced2' (what the proof needs, E001-04).",
    )
    force_bound: float = builder_input(
        0.06, ge=0, description="Stated bound d_bar of the disturbance force |d_i| (1) [N]."
    )
    torque_bound: float = builder_input(
        0.08,
        ge=0,
        description="Stated bound iota_bar of the disturbance torque |iota_i| (4) [N m].",
    )

    @model_validator(mode="after")
    def _sequence(self):
        modes = self.modes
        if modes[0].start != 0.0:
            raise ValueError(f"modes[0].start must be 0 s, got {modes[0].start}")
        if modes[0].variation is not None or modes[0].new_states:
            raise ValueError(
                "modes[0] cannot have a variation matrix or new_states (no previous mode)"
            )
        for j, m in enumerate(modes):
            if j > 0 and m.start <= modes[j - 1].start:
                raise ValueError(
                    f"modes[{j}].start = {m.start} s must be later than modes[{j - 1}].start "
                    f"= {modes[j - 1].start} s"
                )
            for d in m.desired:
                if d.spacecraft not in m.members:
                    raise ValueError(
                        f"modes[{j}].desired: spacecraft {d.spacecraft} is not a member {m.members}"
                    )
            if j > 0:
                self._check_switch(j)
        return self

    def _check_switch(self, j: int) -> None:
        m, prev = self.modes[j], self.modes[j - 1].members
        n_new = len(m.new_states)
        n_rows = len(m.members) - n_new
        if n_rows < 0:
            raise ValueError(
                f"modes[{j}].new_states has {n_new} states but the mode has only "
                f"{len(m.members)} members"
            )
        S = self.variation(j)
        if m.variation is None and list(m.members[:n_rows]) != list(prev):
            raise ValueError(
                f"modes[{j}].variation is required: members {m.members} differ from the "
                f"previous mode's {prev}"
            )
        if S.ndim != 2 or S.shape != (n_rows, len(prev)):
            shape = S.shape if S.ndim == 2 else (len(m.variation or []),)
            raise ValueError(
                f"modes[{j}].variation has shape {shape}; expected ({n_rows}, {len(prev)}) = "
                f"(members of mode {j + 1} not joining via new_states, members of mode {j})"
            )
        if not np.any(S):
            raise ValueError(
                f"modes[{j}].variation must be non-zero (Yang2013 (10): not all spacecraft "
                "may leave at once)"
            )
        for r in range(n_rows):
            if m.members[r] == 0 and np.any(S[r]):
                raise ValueError(
                    f"modes[{j}].members[{r}] = 0 (placeholder) needs a zero row in variation"
                )
        new_ids = [s.spacecraft for s in m.new_states]
        if new_ids != list(m.members[n_rows:]):
            raise ValueError(
                f"modes[{j}].new_states spacecraft {new_ids} must be the last members "
                f"{m.members[n_rows:]} in order"
            )

    def variation(self, j: int) -> np.ndarray:
        """S_ij of the switch mode j-1 -> j (the identity when omitted)."""
        given = self.modes[j].variation
        return np.eye(len(self.modes[j - 1].members)) if given is None else np.asarray(given, float)

    def variation_matrices(self) -> list[np.ndarray]:
        """S_ij for every switch (mode j-1 -> j), j = 1..n_modes-1."""
        return [self.variation(j) for j in range(1, len(self.modes))]

    def switch_times(self) -> list[float]:
        """t_k: the start of every mode [s]."""
        return [m.start for m in self.modes]

    def activation_times(self) -> list[float]:
        """Durations of the modes that are switched out of [s] (the last mode is open-ended)."""
        s = self.switch_times()
        return [s[j + 1] - s[j] for j in range(len(s) - 1)]


class SwitchedStructure(NamedTuple):
    """Slot form of the mode sequence (slot s = spacecraft s + 1): first step of every mode (n_modes,),
    membership (n_modes, N), slot maps P_j of S_ij (n_modes, N, N; P_0 = I unused), new states X*
    (n_modes, N, 13), and members whose state does not continue into the next mode (n_modes, N)."""

    switch_steps: np.ndarray
    active: np.ndarray
    P: np.ndarray
    xstar: np.ndarray
    leaves: np.ndarray


def switched_structure(sec: SwitchingSupervisorSection, count: int, dt: float) -> SwitchedStructure:
    """The mode sequence placed on ``count`` spacecraft slots (variation model (10)).

    Parameters
    ----------
    sec : SwitchingSupervisorSection
        The validated ``[supervisor]`` section.
    count : int
        Number of spacecraft slots N_max.
    dt : float
        Step [s].

    Returns
    -------
    SwitchedStructure
        Switch steps, membership, slot maps P_j, new states X* and leave flags.

    Raises
    ------
    ValueError
        A member beyond the slots, or a switch off the step grid.

    Examples
    --------
    >>> sec = SwitchingSupervisorSection(modes=[
    ...     {"name": "a", "start": 0.0, "members": [1, 2]},
    ...     {"name": "b", "start": 10.0, "members": [1], "variation": [[1.0, 0.0]]}])
    >>> st = switched_structure(sec, 2, 0.5)
    >>> st.switch_steps.tolist(), st.leaves[0].tolist()  # spacecraft 2 leaves at the switch
    ([0, 20], [False, True])
    """
    modes = sec.modes
    n_modes = len(modes)
    active = np.zeros((n_modes, count), dtype=bool)
    for j, m in enumerate(modes):
        if max(m.members) > count:
            raise ValueError(
                f"supervisor.modes[{j}].members: spacecraft {max(m.members)} exceeds plant.count "
                f"= {count}"
            )
        active[j, [s - 1 for s in m.members if s > 0]] = True
    switch_steps = np.array(
        [grid_steps(m.start, dt, f"supervisor.modes[{j}].start") for j, m in enumerate(modes)],
        dtype=np.int64,
    )
    P = np.zeros((n_modes, count, count))
    P[0] = np.eye(count)
    xstar = np.zeros((n_modes, count, STATE_DIM))
    leaves = np.zeros((n_modes, count), dtype=bool)
    for j, S in enumerate(sec.variation_matrices(), start=1):
        m, prev = modes[j], modes[j - 1].members
        for r in range(S.shape[0]):
            if m.members[r] == 0:
                continue
            for c, pc in enumerate(prev):
                if pc > 0:
                    P[j, m.members[r] - 1, pc - 1] = S[r, c]  # Yang2013 eq. (10): S_ij (x) I_13
        for ns in m.new_states:
            xstar[j, ns.spacecraft - 1] = ns.vector()
        for c, pc in enumerate(prev):
            if pc > 0 and not np.any(S[:, c]):
                leaves[j - 1, pc - 1] = True
    return SwitchedStructure(switch_steps, active, P, xstar, leaves)


def _delay_steps(ctx: BuildContext) -> np.ndarray:
    """(N,) a-priori bound of the diagnosis delay [steps]: the ``[estimator]``'s stated ``delay`` [s]
    (a ``scheduled-diagnosis``'s; 0 without one)."""
    delay = getattr(ctx.section("estimator"), "delay", None)
    return np.full(ctx.count, round(delay / ctx.dt) if isinstance(delay, int | float) else 0)


def _build(sec: SwitchingSupervisorSection, ctx: BuildContext) -> SwitchingSupervisor:
    """The supervisor of a validated ``[supervisor] type = "switching"`` section."""
    st = switched_structure(sec, ctx.count, ctx.dt)
    table = []
    for m in sec.modes:  # per mode and slot the three expressions of R~^d(t) [m] (default 0)
        row: list[tuple[str, ...]] = [("0", "0", "0")] * ctx.count
        for d in m.desired:
            row[d.spacecraft - 1] = tuple(str(x) for x in d.position)
        table.append(tuple(row))
    return SwitchingSupervisor(
        count=ctx.count,
        switch_steps=st.switch_steps,
        active=as_float(st.active),
        leaves_at_next_switch=st.leaves,
        eta=as_float(sec.eta),
        eta1=as_float(np.full(ctx.count, sec.eta1)),
        delay_bound_steps=_delay_steps(ctx),
        desired_position=tuple(table),
    )


register(
    "supervisor",
    "switching",
    SwitchingSupervisorSection,
    _build,
    "Yang2013 switching supervisor: prescribed mode sequence, membership, (29) decisions",
)
