"""Scenario schema of method ``yang2013`` (state-varying switched formation, Yang et al. 2013).

A scenario lists the modes in order (``[[modes]]``), each with its start time, its members (the order
of the mode's state vector X_j), the variation matrix S_ij from the previous mode (10) and the new
states X* of spacecraft that join at the switch. Spacecraft are numbered 1..``spacecraft.count``
(1 = main spacecraft); the simulation keeps one slot per spacecraft and an active mask per mode.

Row r of ``variation`` gives the state of ``members[r]`` as a combination of the previous mode's
member states; the remaining members (``members[n_rows:]``) join with the ``new_states`` (X*). A row
of zeros may stand for a departed spacecraft and is then listed as member ``0`` (E001-09).
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from formation_ftc.config.base import ExprText, ScenarioBase, StrictModel

__all__ = [
    "ErrorState",
    "SpacecraftSection",
    "ControllerSection",
    "DisturbanceSection",
    "DesignSection",
    "DesiredPosition",
    "ModeSection",
    "FaultSection",
    "SupervisorSection",
    "Yang2013Scenario",
    "STATE_DIM",
    "NOMINAL_MASS",
    "NOMINAL_INERTIA",
]

STATE_DIM = 13  # x_i = [e_R, e_V, e_w, e_q, e_q4] (7)

Vec3 = tuple[float, float, float]


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
        return np.concatenate([self.e_R, self.e_V, self.e_omega, self.e_q, [self.e_q4]]).astype(
            float
        )


#: the laws' nominal on-board mass [kg] and principal inertia [kg m^2] when a scenario states none
#: (``controller.nominal_mass``, ``controller.nominal_inertia``): the paper's spacecraft (E001-10)
NOMINAL_MASS = 150.0
NOMINAL_INERTIA = (25.0, 25.0, 25.0)


class SpacecraftSection(StrictModel):
    count: int = Field(
        ge=1, le=64, description="Number of spacecraft slots N_max (numbered 1..count) [-]."
    )
    mass: float = Field(
        150.0,
        gt=0,
        description="True mass M_i of every spacecraft [kg] (truth; the laws use "
        "controller.nominal_mass).",
    )
    inertia: tuple[float, float, float] = Field(
        (25.0, 25.0, 25.0),
        description="True principal inertia diag(J_i) of every spacecraft [kg m^2] (truth; the "
        "laws use controller.nominal_inertia).",
    )

    @field_validator("inertia")
    @classmethod
    def _positive_inertia(cls, v):
        if min(v) <= 0:
            raise ValueError(f"spacecraft.inertia must be > 0 kg m^2 on every axis, got {v}")
        return v


class ControllerSection(StrictModel):
    """Gains of (12)-(13); positive (E001-01)."""

    K1: float = Field(0.005, gt=0, description="Position gain offset K1 (e_R gain K1+1) [1/s^2].")
    K2: float = Field(0.01, gt=0, description="Velocity gain K2 [1/s].")
    K3: float = Field(0.2, gt=0, description="Angular-rate gain K3 [1/s].")
    K4: float = Field(1.0, gt=0, description="Quaternion-vector shaping gain K4 [1/s].")
    K5: float = Field(1.0, gt=0, description="Quaternion-scalar shaping gain K5 [1/s].")
    kappa: float = Field(1e-3, gt=0, description="Smoothing constant kappa of (13) [rad^2/s^2].")
    nominal_mass: float = Field(
        NOMINAL_MASS,
        gt=0,
        description=(
            "Mass M_i the translational law (12) knows on board [kg] (default 150 kg, a stated nominal value: never "
            "the true spacecraft.mass). Also the mass of the faulty law's K2 -> K2f term."
        ),
    )
    nominal_inertia: tuple[float, float, float] = Field(
        NOMINAL_INERTIA,
        description=(
            "Principal inertia diag(J_i) the attitude law (13) knows on board [kg m^2], each > 0 (default 25, 25, "
            "25 kg m^2, a stated nominal value: never the true spacecraft.inertia)."
        ),
    )
    rotation_coupling: bool = Field(
        True,
        description="Keep the norm-preserving omega_i x e terms of (2) with omega_i = -e_omega "
        "(reference at rest); false drops them (the terms preserve the error norm).",
    )

    @field_validator("nominal_inertia")
    @classmethod
    def _positive_nominal_inertia(cls, v):
        if min(v) <= 0:
            raise ValueError(
                f"controller.nominal_inertia must be > 0 kg m^2 on every axis, got {v}"
            )
        return v


class DisturbanceSection(StrictModel):
    force: tuple[ExprText, ExprText, ExprText] = Field(
        ("0", "0", "0"),
        description="Disturbance force d_i(t) per axis; expressions in t [s] and i [N].",
    )
    torque: tuple[ExprText, ExprText, ExprText] = Field(
        ("0", "0", "0"),
        description="Disturbance torque iota_i(t) per axis; expressions in t, i [N m].",
    )
    force_bound: float = Field(0.06, ge=0, description="Bound d_bar of |d_i| [N].")
    torque_bound: float = Field(0.08, ge=0, description="Bound iota_bar of |iota_i| [N m].")


class DesignSection(StrictModel):
    """Design constants of Theorems 1-2 (the paper gives zeta, eta as controller design outcomes)."""

    zeta: float = Field(5.0, gt=0, description="zeta = max_j sqrt(n_j eps) of (20) [-].")
    eta: float = Field(0.01, gt=0, description="Decay rate eta of (20) [1/s].")
    eta1: float = Field(
        0.01, ge=0, description="Growth rate eta1 of the faulty dynamics (28) [1/s]."
    )
    epsilon: float = Field(0.9, gt=0, description="epsilon of Theorem 1 [-].")
    epsilon1: float = Field(0.2, gt=0, description="epsilon_1 of (21) [-].")
    epsilon2: float = Field(0.4, ge=0, description="epsilon_2 of (22) [-].")
    dwell_time: float = Field(80.0, ge=0, description="Dwell time tau of (21) [s].")
    variation_norm: Literal["frobenius", "induced2"] = Field(
        "frobenius",
        description="Norm used for S = max|S_ij|: 'frobenius' (paper, sqrt 5) or "
        "'induced2' (what the proof needs, E001-04).",
    )


class DesiredPosition(StrictModel):
    spacecraft: int = Field(ge=1, description="Spacecraft number [-].")
    position: tuple[ExprText, ExprText, ExprText] = Field(
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
        description="New states X* of the spacecraft joining at this switch (10).",
    )
    desired: list[DesiredPosition] = Field(
        default_factory=list, description="Desired relative positions in this mode (default 0)."
    )

    @field_validator("members")
    @classmethod
    def _members_nonempty(cls, v, info):
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


class FaultSection(StrictModel):
    """Velocity-channel controller fault K2 -> K2f (Yang2013 Sec. 4)."""

    spacecraft: int = Field(ge=1, description="Faulty spacecraft number [-].")
    onset: float = Field(ge=0, description="Fault onset time t_f [s] (snapped to the step grid).")
    K2_faulty: float = Field(-0.01, description="Faulty velocity gain K2f [1/s].")
    diagnosis_delay: float = Field(
        0.0,
        ge=0,
        description="Delay between onset and diagnosis [s]; its "
        "a-priori bound is counted in dt2 of (29).",
    )


class SupervisorSection(StrictModel):
    reconfiguration: Literal["restore_nominal", "none"] = Field(
        "restore_nominal",
        description="What a reconfiguration request does: the reconfigured "
        "controller uses the nominal K2 ('restore_nominal', ideal) or nothing changes ('none').",
    )


class Yang2013Scenario(ScenarioBase):
    spacecraft: SpacecraftSection
    controller: ControllerSection = ControllerSection()
    disturbance: DisturbanceSection = DisturbanceSection()
    design: DesignSection = DesignSection()
    initial_state: list[ErrorState] = Field(description="x_i(0) of the first mode's members.")
    modes: list[ModeSection] = Field(min_length=1, description="Mode sequence in switching order.")
    faults: list[FaultSection] = Field(default_factory=list, description="Controller faults.")
    supervisor: SupervisorSection = SupervisorSection()

    @model_validator(mode="after")
    def _consistency(self) -> Yang2013Scenario:
        n = self.spacecraft.count
        dt = self.simulation.dt
        modes = (
            self.modes
        )  # modes starting at or after simulation.horizon are never reached (short runs)
        if modes[0].start != 0.0:
            raise ValueError(f"modes[0].start must be 0 s, got {modes[0].start}")
        if modes[0].variation is not None or modes[0].new_states:
            raise ValueError(
                "modes[0] cannot have a variation matrix or new_states (no previous mode)"
            )
        for j, m in enumerate(modes):
            for sc in m.members:
                if sc > n:
                    raise ValueError(
                        f"modes[{j}].members: spacecraft {sc} exceeds spacecraft.count = {n}"
                    )
            k = m.start / dt
            if abs(k - round(k)) > 1e-9 * max(1.0, k):
                raise ValueError(
                    f"modes[{j}].start = {m.start} s is not a multiple of simulation.dt = {dt} s"
                )
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
            if j == 0:
                continue
            prev = modes[j - 1].members
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
            if 0 in new_ids:
                raise ValueError(f"modes[{j}].new_states cannot be placeholders (0)")
        first = [s.spacecraft for s in self.initial_state]
        if sorted(first) != sorted(x for x in modes[0].members if x > 0):
            raise ValueError(
                f"initial_state must give exactly the members of modes[0] {modes[0].members}, "
                f"got spacecraft {first}"
            )
        for f in self.faults:
            if f.spacecraft > n:
                raise ValueError(
                    f"faults[].spacecraft = {f.spacecraft} exceeds spacecraft.count = {n}"
                )
            k = f.onset / dt
            if abs(k - round(k)) > 1e-9 * max(1.0, k):
                raise ValueError(
                    f"faults[].onset = {f.onset} s is not a multiple of simulation.dt = {dt} s"
                )
        return self

    # ------------------------------------------------------------------ derived structure
    def variation_matrices(self) -> list[np.ndarray]:
        """S_ij for every switch (mode j-1 -> j), j = 1..n_modes-1."""
        out = []
        for j in range(1, len(self.modes)):
            m = self.modes[j]
            if m.variation is None:
                out.append(np.eye(len(self.modes[j - 1].members)))
            else:
                out.append(np.asarray(m.variation, dtype=float))
        return out

    def mode_sizes(self) -> list[int]:
        """n_j: number of state blocks of each mode (placeholders included, E001-09)."""
        return [len(m.members) for m in self.modes]

    def switch_times(self) -> list[float]:
        return [m.start for m in self.modes]

    def activation_times(self) -> list[float]:
        """Durations of the modes that are switched out of (the last mode is open-ended)."""
        s = self.switch_times()
        return [s[j + 1] - s[j] for j in range(len(s) - 1)]
