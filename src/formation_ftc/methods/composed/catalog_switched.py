"""Catalog: Yang2013's state-varying switched formation at the closed-loop error level.

The laws (12)-(13) cancel the drift terms Phi_i, Upsilon_i of (2), (5) exactly (E001-02), so the
closed-loop error dynamics are exact for any orbit; these types simulate them at the error level:

* plant ``switched-formation`` (:class:`~formation_ftc.components.plants.switched_formation.
  SwitchedFormationPlant`): N_max slots (spacecraft 1..``count``, 1 = main) with the error dynamics,
  the true disturbances, and membership and state variation (10) at every switch of the
  ``[supervisor]``'s mode sequence (the plan the truth executes);
* sensors ``tracking-error``, controller ``yang2013-force-torque`` (laws (12) and (13) side by side),
  actuator ``velocity-gain-fault`` (the controller fault K2 -> K2f of Sec. 4, truth side), estimator
  ``scheduled-diagnosis`` (the diagnosis, onset + delay, the supervisor sees);
* supervisor ``switching``: the prescribed mode sequence ``[[supervisor.modes]]`` (start, members,
  variation S_ij (10), new states X*, desired relative positions), membership and the (29) decisions,
  with the design constants of Theorems 1-2 that ``formation-ftc check`` states;
* ``[[evaluations]] type = "switch-norms"``: metrics only -- sup |X| over both limits of every switch,
  |X| at both limits of every switch (per spacecraft before it), final |X|, max |u_i|, the decisions.

Row r of a mode's ``variation`` gives the state of ``members[r]`` as a combination of the previous
mode's member states; the remaining members (``members[n_rows:]``) join with the ``new_states`` (X*). A
row of zeros may stand for a departed spacecraft and is then listed as member ``0`` (E001-09).
"""

from __future__ import annotations

from typing import Literal, NamedTuple

import numpy as np
from pydantic import Field, PositiveFloat, field_validator, model_validator

from formation_ftc.components._flight_defaults import NOMINAL_INERTIA
from formation_ftc.components.controllers.yang2013_attitude import yang2013_attitude_law
from formation_ftc.components.plants.quaternion_rigid_body import quaternion_plant
from formation_ftc.config.base import ExprText, StrictModel
from formation_ftc.methods.composed import (
    BuildContext,
    per_spacecraft,
    register_component_type,
)
from formation_ftc.methods.composed.catalog_delays import NOMINAL_MASS, translational_law
from formation_ftc.sim.contract import CompositionError, as_float

__all__ = ["SWITCHED_PLANT", "SWITCHING_SUPERVISOR", "YANG2013_FORCE_TORQUE", "switched_structure"]

SWITCHED_PLANT = "switched-formation"
SWITCHING_SUPERVISOR = "switching"
YANG2013_FORCE_TORQUE = "yang2013-force-torque"

Vec3 = tuple[float, float, float]
PositiveVec3 = tuple[PositiveFloat, PositiveFloat, PositiveFloat]
Vec3Expr = tuple[ExprText, ExprText, ExprText]


def _on_grid(value: float, dt: float) -> bool:
    k = value / dt
    return abs(k - round(k)) <= 1e-9 * max(1.0, k)


# ------------------------------------------------------------------------------------------ plant
class ErrorState(StrictModel):
    """Error state x_i of one spacecraft (7): desired minus actual, in the body frame F_i."""

    spacecraft: int = Field(ge=1, description="Spacecraft number (1 = main spacecraft) [-].")
    e_R: Vec3 = Field((0.0, 0.0, 0.0), description="Relative position error e_R [m].")
    e_V: Vec3 = Field((0.0, 0.0, 0.0), description="Relative velocity error e_V [m/s].")
    e_omega: Vec3 = Field((0.0, 0.0, 0.0), description="Angular velocity error e_omega [rad/s].")
    e_q: Vec3 = Field((0.0, 0.0, 0.0), description="Quaternion vector error e_q [-].")
    e_q4: float = Field(0.0, description="Quaternion scalar error e_q4 [-] (E001-03: start at 0).")

    def vector(self) -> np.ndarray:
        """The 13-vector x_i."""
        return np.array([*self.e_R, *self.e_V, *self.e_omega, *self.e_q, self.e_q4], dtype=float)


class SwitchedFormationSection(StrictModel):
    """Truth of the switched formation: slots, masses, inertia, disturbances, initial error states."""

    count: int = Field(
        ge=1, le=64, description="Number of spacecraft slots N_max (numbered 1..count) [-]."
    )
    mass: float = Field(
        150.0,
        gt=0,
        description="True mass M_i of every spacecraft [kg] (the laws use their stated "
        "controller.nominal_mass).",
    )
    inertia: PositiveVec3 = Field(
        (25.0, 25.0, 25.0),
        description="True principal inertia diag(J_i) of every spacecraft [kg m^2] (the laws use "
        "their stated controller.nominal_inertia).",
    )
    rotation_coupling: bool = Field(
        True,
        description="Keep the norm-preserving omega_i x e terms of (2) with omega_i = -e_omega "
        "(reference at rest); false drops them (the terms preserve the error norm).",
    )
    disturbance_force: Vec3Expr = Field(
        ("0", "0", "0"),
        description="Disturbance force d_i(t) per axis; expressions in t [s] and i [N].",
    )
    disturbance_torque: Vec3Expr = Field(
        ("0", "0", "0"),
        description="Disturbance torque iota_i(t) per axis; expressions in t [s] and i [N m].",
    )
    initial_state: list[ErrorState] = Field(
        description="x_i(0) of the first mode's members (the other slots start at 0)."
    )


# ------------------------------------------------------------------------------------- supervisor
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

    modes: list[ModeSection] = Field(min_length=1, description="Mode sequence in switching order.")
    eta: float = Field(0.01, gt=0, description="Decay rate eta of the healthy modes (20) [1/s].")
    eta1: float = Field(
        0.01, ge=0, description="Growth rate eta1 of the faulty dynamics (28) [1/s]."
    )
    zeta: float = Field(5.0, gt=0, description="zeta = max_j sqrt(n_j eps) of (20) [-].")
    epsilon: float = Field(0.9, gt=0, description="epsilon of Theorem 1 [-].")
    epsilon1: float = Field(0.2, gt=0, description="epsilon_1 of (21) [-].")
    epsilon2: float = Field(0.4, ge=0, description="epsilon_2 of (22) [-].")
    dwell_time: float = Field(80.0, ge=0, description="Dwell time tau of (21) [s].")
    variation_norm: Literal["frobenius", "induced2"] = Field(
        "frobenius",
        description="Norm used for S = max|S_ij|: 'frobenius' (paper, sqrt 5) or "
        "'induced2' (what the proof needs, E001-04).",
    )
    force_bound: float = Field(
        0.06, ge=0, description="Stated bound d_bar of the disturbance force |d_i| (1) [N]."
    )
    torque_bound: float = Field(
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
        S = np.eye(len(prev)) if m.variation is None else np.asarray(m.variation, dtype=float)
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

    def variation_matrices(self) -> list[np.ndarray]:
        """S_ij for every switch (mode j-1 -> j), j = 1..n_modes-1."""
        return [
            np.eye(len(self.modes[j - 1].members))
            if self.modes[j].variation is None
            else np.asarray(self.modes[j].variation, dtype=float)
            for j in range(1, len(self.modes))
        ]

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
    """The mode sequence placed on ``count`` spacecraft slots with step ``dt`` [s] (variation model
    (10)); a member beyond the slots or a switch off the step grid is an error."""
    from formation_ftc.components.plants.switched_formation import STATE_DIM

    modes = sec.modes
    n_modes = len(modes)
    for j, m in enumerate(modes):
        if max(m.members) > count:
            raise ValueError(
                f"supervisor.modes[{j}].members: spacecraft {max(m.members)} exceeds plant.count "
                f"= {count}"
            )
        if not _on_grid(m.start, dt):
            raise ValueError(
                f"supervisor.modes[{j}].start = {m.start} s is not a multiple of simulation.dt = "
                f"{dt} s"
            )
    switch_steps = np.array([round(m.start / dt) for m in modes], dtype=np.int64)
    active = np.zeros((n_modes, count), dtype=bool)
    for j, m in enumerate(modes):
        active[j, [s - 1 for s in m.members if s > 0]] = True
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


def _plan(ctx: BuildContext, who: str) -> SwitchingSupervisorSection:
    """The switching supervisor's section (the mode sequence) that ``who`` needs."""
    kind = ctx.scenario.type_of("supervisor")
    if kind != SWITCHING_SUPERVISOR:
        raise CompositionError(
            f"{who} reads the mode sequence of a [supervisor] of type {SWITCHING_SUPERVISOR!r}, "
            f"but the loop's supervisor is {kind or 'missing'}: add one"
        )
    return ctx.section("supervisor")


def _switched_formation(sec: SwitchedFormationSection, ctx: BuildContext):
    from formation_ftc.components.plants.switched_formation import STATE_DIM, SwitchedFormationPlant

    plan = _plan(ctx, f"plant {SWITCHED_PLANT}")
    st = switched_structure(plan, sec.count, ctx.dt)
    first = sorted(s.spacecraft for s in sec.initial_state)
    if first != sorted(x for x in plan.modes[0].members if x > 0):
        raise ValueError(
            f"plant.initial_state must give exactly the members of supervisor.modes[0] "
            f"{plan.modes[0].members}, got spacecraft {first}"
        )
    x0 = np.zeros((sec.count, STATE_DIM))
    for init in sec.initial_state:
        x0[init.spacecraft - 1] = init.vector()
    px, py, pz = sec.disturbance_force
    # the attitude error dynamics (5): no gyroscopic term (part of the drift the law (13) cancels)
    attitude = quaternion_plant(
        sec.inertia, x0[:, 6:9], x0[:, 9:13], sec.disturbance_torque, gyroscopic=False
    )
    return SwitchedFormationPlant(
        mass=as_float(per_spacecraft(sec.mass, sec.count, "plant.mass")),
        attitude=attitude,
        initial_translation=as_float(x0[:, 0:6]),
        variation=as_float(st.P),
        new_states=as_float(st.xstar),
        disturbance_force=(str(px), str(py), str(pz)),
        rotation_coupling=sec.rotation_coupling,
    )


def _switching_supervisor(sec: SwitchingSupervisorSection, ctx: BuildContext):
    from formation_ftc.components.supervisors.switching_supervisor import SwitchingSupervisor

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


# ------------------------------------------------------------------------------ sensors, controller
class TrackingErrorSection(StrictModel):
    """Exact measurement of the error state; no fields."""


def _tracking_error(sec: TrackingErrorSection, ctx: BuildContext):
    from formation_ftc.components.sensors.tracking_error import TrackingErrorSensors

    if ctx.scenario.type_of("plant") != SWITCHED_PLANT:
        raise CompositionError(
            f"sensors tracking-error read the error state of plant {SWITCHED_PLANT}, but the "
            f"plant is {ctx.scenario.type_of('plant')}"
        )
    return TrackingErrorSensors(count=ctx.count)


class Yang2013ForceTorqueSection(StrictModel):
    """Gains of (12)-(13); positive (E001-01); the laws' stated on-board mass and inertia."""

    K1: float = Field(0.005, gt=0, description="Position gain offset K1 (e_R gain K1+1) [1/s^2].")
    K2: float = Field(0.01, gt=0, description="Velocity gain K2 [1/s].")
    K3: float = Field(0.2, gt=0, description="Angular-rate gain K3 [1/s].")
    K4: float = Field(1.0, gt=0, description="Quaternion-vector shaping gain K4 [1/s].")
    K5: float = Field(1.0, gt=0, description="Quaternion-scalar shaping gain K5 [1/s].")
    kappa: float = Field(1e-3, gt=0, description="Smoothing constant kappa of (13) [rad^2/s^2].")
    nominal_mass: float = Field(
        NOMINAL_MASS,
        gt=0,
        description="Mass M_i the translational law (12) knows on board [kg] (default 150 kg, a "
        "stated nominal value: never the plant's true mass). Also the mass of the faulty law's "
        "K2 -> K2f term.",
    )
    nominal_inertia: PositiveVec3 = Field(
        NOMINAL_INERTIA,
        description="Principal inertia diag(J_i) the attitude law (13) knows on board [kg m^2], each "
        "> 0 (default 25, 25, 25 kg m^2, a stated nominal value: never the plant's true inertia).",
    )


def _yang2013_force_torque(sec: Yang2013ForceTorqueSection, ctx: BuildContext):
    from formation_ftc.components.controllers.force_torque import ForceTorqueController

    if ctx.scenario.type_of("sensors") != "tracking-error":
        raise CompositionError(
            f"controller {YANG2013_FORCE_TORQUE} acts on the error state (translation, omega, q) of "
            f"sensors tracking-error, but the loop's sensors are {ctx.scenario.type_of('sensors')}"
        )
    return ForceTorqueController(
        force_law=translational_law(ctx, sec.nominal_mass, sec.K1, sec.K2),  # eq. (12)
        torque_law=yang2013_attitude_law(
            ctx, sec.nominal_inertia, sec.K3, sec.K4, sec.K5, sec.kappa
        ),  # eq. (13)
    )


# -------------------------------------------------------------------------- fault, diagnosis
class VelocityFault(StrictModel):
    """Velocity-channel controller fault K2 -> K2f (Yang2013 Sec. 4)."""

    spacecraft: int = Field(ge=1, description="Faulty spacecraft number [-].")
    onset: float = Field(ge=0, description="Fault onset time t_f [s] (a multiple of the step).")
    K2_faulty: float = Field(-0.01, description="Faulty velocity gain K2f [1/s].")


class VelocityGainFaultSection(StrictModel):
    """Controller faults of the truth side; the faulty unit uses the law's K2 and stated mass."""

    faults: list[VelocityFault] = Field(
        default_factory=list, description="Controller faults (none: a healthy unit)."
    )
    reconfiguration: Literal["restore_nominal", "none"] = Field(
        "restore_nominal",
        description="What a reconfiguration request of the supervisor does: the reconfigured "
        "controller uses the nominal K2 ('restore_nominal', ideal) or nothing changes ('none').",
    )


def _fault_steps(ctx: BuildContext) -> dict[int, tuple[int, float]]:
    """slot -> (onset step, K2f) of the actuator's faults (checked against the slots and the grid)."""
    out = {}
    for f in getattr(ctx.section("actuator"), "faults", []):
        if f.spacecraft > ctx.count:
            raise ValueError(
                f"actuator.faults: spacecraft {f.spacecraft} exceeds plant.count = {ctx.count}"
            )
        if not _on_grid(f.onset, ctx.dt):
            raise ValueError(
                f"actuator.faults: onset = {f.onset} s is not a multiple of simulation.dt = "
                f"{ctx.dt} s"
            )
        out[f.spacecraft - 1] = (round(f.onset / ctx.dt), f.K2_faulty)
    return out


def _velocity_gain_fault(sec: VelocityGainFaultSection, ctx: BuildContext):
    from formation_ftc.components.actuators.velocity_gain_fault import VelocityGainFaultActuator

    law = ctx.section("controller")
    if not all(hasattr(law, k) for k in ("K2", "nominal_mass")):
        raise CompositionError(
            f"actuator velocity-gain-fault replaces the velocity gain K2 of the law (12), but "
            f"controller {ctx.scenario.type_of('controller')} has none (use "
            f"{YANG2013_FORCE_TORQUE})"
        )
    n = ctx.count
    onset = np.full(n, np.inf)
    K2f = np.full(n, law.K2)
    for s, (k_f, k2f) in _fault_steps(ctx).items():
        onset[s], K2f[s] = k_f * ctx.dt, k2f  # on the step grid: t_k as the loop computes it
    return VelocityGainFaultActuator(  # the faulty law's extra force M_i (K2f - K2) e_V
        count=n,
        mass=as_float(per_spacecraft(law.nominal_mass, n, "controller.nominal_mass")),
        K2=as_float(law.K2),
        K2_faulty=as_float(K2f),
        onset=as_float(onset),
        reconfigurable=sec.reconfiguration == "restore_nominal",
    )


class ScheduledDiagnosisSection(StrictModel):
    """FDI unit modelled by its diagnosis delay after the actuator's fault onsets."""

    delay: float = Field(
        0.0,
        ge=0,
        description="Diagnosis delay after the fault onset [s] (snapped to the step grid); the "
        "switching supervisor counts it as the a-priori bound in dt2 of (29).",
    )


def _delay_steps(ctx: BuildContext) -> np.ndarray:
    """(N,) diagnosis delay of the scheduled diagnosis [steps] (0 without one)."""
    known = ctx.scenario.type_of("estimator") == "scheduled-diagnosis"
    return np.full(ctx.count, round(ctx.section("estimator").delay / ctx.dt) if known else 0)


def _scheduled_diagnosis(sec: ScheduledDiagnosisSection, ctx: BuildContext):
    from formation_ftc.components.estimators.scheduled_diagnosis import ScheduledDiagnosis

    delay = _delay_steps(ctx)
    diagnosis = np.full(ctx.count, np.inf)
    for s, (k_f, _) in _fault_steps(ctx).items():
        diagnosis[s] = (k_f + delay[s]) * ctx.dt
    return ScheduledDiagnosis(count=ctx.count, diagnosis_time=as_float(diagnosis))


# ------------------------------------------------------------------------------------ evaluation
class SwitchNormsSection(StrictModel):
    """Metrics of the switched loop (module docstring), and maxima of |u_i| on stated windows."""

    input_windows: list[tuple[float, float]] = Field(
        default_factory=list,
        description="Windows [a, b) [s] of further every-step maxima of |u_i| per spacecraft "
        "(metrics max_input_norm_<a>_<b>_sc<i>).",
    )


def _switch_norms(sec: SwitchNormsSection, ctx: BuildContext):
    from formation_ftc.sim.metrics import Metric

    plan = _plan(ctx, "evaluation switch-norms")  # with plant switched-formation (its signals)
    st = switched_structure(plan, ctx.count, ctx.dt)
    n_steps = ctx.scenario.simulation.n_steps
    ctx.metrics.extend(
        [
            Metric("max_state_norm", "state_norm_peak", reduce="max", units="1"),
            Metric("final_state_norm", "state_norm", reduce="final", units="1"),
        ]
    )
    windows = [("max_input_norm", 0.0, n_steps * ctx.dt)]  # [0, horizon), then the stated ones
    for name, a, b in windows + [
        (f"max_input_norm_{a:g}_{b:g}", a, b) for a, b in sec.input_windows
    ]:
        ctx.metrics.append(  # every step of [a, b): the window ends half a step before b
            Metric(
                name,
                "input_norm",
                "max",
                spacecraft="each",
                units="1",
                start=as_float(a),
                end=as_float(b - 0.5 * ctx.dt),
            )
        )
    for j in range(1, len(st.switch_steps)):
        if st.switch_steps[j] > n_steps:  # never reached (short runs)
            continue
        t = as_float(st.switch_steps[j] * ctx.dt)
        ctx.metrics.extend(
            [
                Metric(f"pre_switch_norm_{j + 1}", "state_norm_left", "at", units="1", start=t),
                Metric(f"post_switch_norm_{j + 1}", "state_norm", "at", units="1", start=t),
                Metric(
                    f"pre_switch_sc_norm_{j + 1}",
                    "spacecraft_norm_left",
                    "at",
                    spacecraft="each",
                    units="1",
                    start=t,
                ),
            ]
        )
    # decision codes (0 none, 1 tolerate by switching, 2 reconfigure); times, modes and (29) margins
    # are recorded signals (the last record holds every decision)
    ctx.metrics.append(
        Metric("supervisor_decision", "supervisor_decision", reduce="final", spacecraft="each")
    )
    return None


for _kind, _name, _section, _build, _text in (
    ("plant", SWITCHED_PLANT, SwitchedFormationSection, _switched_formation, "Yang2013 error "
     "dynamics (2), (5) of N_max slots, membership and state variation (10) at the plan's switches"),
    ("sensors", "tracking-error", TrackingErrorSection, _tracking_error, "exact error state"),
    ("controller", YANG2013_FORCE_TORQUE, Yang2013ForceTorqueSection, _yang2013_force_torque,
     "Yang2013 laws (12)-(13) side by side: wrench on the error state"),
    ("actuator", "velocity-gain-fault", VelocityGainFaultSection, _velocity_gain_fault,
     "controller fault K2 -> K2f of the law (12) (Yang2013 Sec. 4), reconfigurable"),
    ("estimator", "scheduled-diagnosis", ScheduledDiagnosisSection, _scheduled_diagnosis,
     "FDI unit diagnosing the actuator's faults after a stated delay"),
    ("supervisor", SWITCHING_SUPERVISOR, SwitchingSupervisorSection, _switching_supervisor,
     "Yang2013 switching supervisor: prescribed mode sequence, membership, (29) decisions"),
    ("evaluation", "switch-norms", SwitchNormsSection, _switch_norms,
     "|X| at both limits of every switch, sup |X|, max |u_i|, decisions (metrics only)"),
):  # fmt: skip
    register_component_type(_kind, _name, _section, _build, _text)
