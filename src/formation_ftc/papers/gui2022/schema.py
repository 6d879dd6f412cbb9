"""Scenario schema of method ``gui2022`` (Gui et al. 2022).

One chief on a circular orbit and one deputy on linear CW dynamics with thruster bias faults F(t)
(H = B), the space perturbation d(t) of ref. [12], the iterative learning observer (5) and one of the
controllers ``none`` (u = 0, section 5.1), ``lof2tc`` (30)-(32) or ``cof2tc`` (the conventional baseline).
Defaults are the paper's printed values; where the paper is silent this project's documented choices.
Units: u, d, F in m/s^2 (per unit mass, E002-03); positions m, velocities m/s, times s.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from formation_ftc.blocks.observers.iterative_learning_observer import (
    LearningIntervalError,
    learning_steps,
)
from formation_ftc.config.base import ScenarioBase, StrictModel
from formation_ftc.papers.gui2022 import published as pub

__all__ = [
    "Gui2022Scenario",
    "OrbitSection",
    "DisturbanceSection",
    "FaultSection",
    "InitialSection",
    "ObserverSection",
    "ControllerSection",
    "MetricsSection",
]

Vec3 = tuple[float, float, float]
Vec6 = tuple[float, float, float, float, float, float]


def _matrix(value, shape, field):
    arr = np.asarray(value, dtype=float)
    if arr.shape != shape:
        raise ValueError(
            f"{field}: expected a {shape[0]}x{shape[1]} matrix (list of rows), got shape {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{field}: entries must be finite")
    return arr.tolist()


class OrbitSection(StrictModel):
    mean_motion: float = Field(
        pub.N_MEAN_MOTION, gt=0, description="Mean motion n of the chief's circular orbit [rad/s]."
    )


class DisturbanceSection(StrictModel):
    amplitude: float = Field(
        pub.A0,
        ge=0,
        description=(
            "A0 of d(t) = A0 [1 - 1.5 sin nt, 0.5 sin 2nt, sin nt] (ref. [12]) [m/s^2]; 0 disables it."
        ),
    )


class FaultSection(StrictModel):
    """Thruster bias faults F(t) (section 5): step on x, sinusoid minus decaying exponential on z."""

    x_onset: float = Field(
        1500.0, ge=0, description="Onset of the x step fault (snapped to the step grid) [s]."
    )
    x_magnitude: float = Field(0.5, description="F_x after the onset [m/s^2].")
    y_onset: float = Field(0.0, ge=0, description="Onset of the y step fault [s] (paper: F_y = 0).")
    y_magnitude: float = Field(0.0, description="F_y after the onset [m/s^2].")
    z_onset: float = Field(2000.0, ge=0, description="Onset of the z time-varying fault [s].")
    z_amplitude: float = Field(0.25, description="Amplitude of 0.25 sin(0.05 t + pi/4) [m/s^2].")
    z_omega: float = Field(0.05, description="Angular frequency of the z fault [rad/s].")
    z_phase: float = Field(math.pi / 4, description="Phase of the z fault [rad].")
    z_decay_amplitude: float = Field(
        -0.2, description="Coefficient of the exponential term (-0.2 e^{-0.1 t}) [m/s^2]."
    )
    z_decay_rate: float = Field(0.1, ge=0, description="Rate of the exponential term [1/s].")
    z_decay_shifted: bool = Field(
        False,
        description=(
            "E002-09: false = literal e^{-0.1 t} (~0 after 2000 s); true = e^{-0.1 (t - z_onset)} (probable intent)."
        ),
    )


class InitialSection(StrictModel):
    desired_state: Vec6 = Field(
        tuple(pub.Q0_INITIAL), description="q0(0) of the nominal orbit (28) [m, m/s]."
    )
    state: Vec6 = Field(
        (0.0,) * 6,
        description="Truth: q(0) of the deputy [m, m/s] (the observer starts from "
        "observer.initial_estimate, never from this).",
    )

    @model_validator(mode="before")
    @classmethod
    def _offset_moved(cls, data):
        if isinstance(data, dict) and "estimate_offset" in data:
            raise ValueError(
                "initial.estimate_offset (q_hat(0) - q(0)) was replaced by observer.initial_estimate, "
                "the observer's own q_hat(0) [m, m/s]: give observer.initial_estimate = initial.state "
                "+ the offset (the flight side never reads the true initial state)"
            )
        return data


class ObserverSection(StrictModel):
    """ILO (5) and the Theorem 1 design data (for `check`)."""

    gains: Literal["printed", "lmi"] = Field(
        "printed",
        description=(
            "'printed' = the paper's L1, L2 (used to reproduce); 'lmi' = solve (8), (27) and the disk LMI."
        ),
    )
    L1: list[list[float]] = Field(
        pub.L1_PRINTED.tolist(),
        description="Observer gain L1 (6x6) [1/s] (used when gains = 'printed').",
    )
    L2: list[list[float]] = Field(
        pub.L2_PRINTED.tolist(),
        description="Learning gain L2 (3x6) [1/s] (used when gains = 'printed').",
    )
    lmi_scale: float = Field(
        1.0,
        gt=0,
        description=(
            "Free scale s of the homogeneous LMIs: (P, Y, L2) -> s (P, Y, L2) after the normalised solve (P >= I) [-]."
        ),
    )
    Q1: Vec3 = Field(tuple(pub.Q1_PRINTED), description="Diagonal of Q1, each in (0, 1] [-].")
    Q2: float = Field(pub.Q2_PRINTED, gt=0, description="Learning gain Q2 = 1/(beta eta) [-].")
    gamma: float = Field(
        pub.GAMMA_PRINTED,
        ge=0,
        description="Sign-term gain gamma, (11) needs gamma >= d_max [m/s^2].",
    )
    sign_term: bool = Field(
        True, description="Include gamma sgn(e_y) (false = the ILO of ref. [25], Fig. 6 baseline)."
    )
    learning_interval: float = Field(
        0.001, gt=0, description="tau: integer multiple of simulation.dt [s]."
    )
    mu: float = Field(pub.MU, gt=0, description="mu of Theorem 1 (eta = 1 + mu) [-].")
    gamma1: float = Field(pub.GAMMA1, gt=0, description="gamma_1 of (10) [-].")
    beta: float = Field(pub.BETA, gt=0, description="beta of (17) (Q2 = 1/(beta eta)) [-].")
    lmi_lambda: float = Field(1e-8, gt=0, description="lambda of (27) [-].")
    disk_center: float = Field(
        -5.0,
        description=(
            "Centre c of the pole region S(c, r) [1/s] (a region in the right half plane makes the LMI infeasible)."
        ),
    )
    disk_radius: float = Field(2.0, gt=0, description="Radius r of the pole region S(c, r) [1/s].")
    initial_estimate: Vec6 = Field(
        (0.0,) * 6,
        description=(
            "q_hat(0), the ILO's initial state estimate [m, m/s] (default 0: a zero initial estimate, a stated "
            "value, never the true initial.state; the Figs. 4-5 run starts from an offset estimate with q(0) = 0)."
        ),
    )

    @field_validator("L1")
    @classmethod
    def _l1(cls, v):
        return _matrix(v, (6, 6), "observer.L1")

    @field_validator("L2")
    @classmethod
    def _l2(cls, v):
        return _matrix(v, (3, 6), "observer.L2")

    @field_validator("Q1")
    @classmethod
    def _q1(cls, v):
        for k, s in enumerate(v):
            if not 0 < s <= 1:
                raise ValueError(f"observer.Q1[{k}] = {s}: each sigma_i must be in (0, 1]")
        return v


class ControllerSection(StrictModel):
    """Controller slot: none (u = 0), LOF2TC (30)-(32) or the COF2TC baseline."""

    law: Literal["none", "lof2tc", "cof2tc"] = Field(
        "lof2tc", description="'none' (u = 0), 'lof2tc' or 'cof2tc'."
    )
    gains: Literal["printed", "care"] = Field(
        "printed", description="K: printed, or B^T P1 from the CARE (34) with Q = care_q_scale I6."
    )
    K: list[list[float]] = Field(
        pub.K_PRINTED.tolist(), description="Gain K (3x6) [1/s^2, 1/s] (gains = 'printed')."
    )
    care_q_scale: float = Field(
        pub.CARE_Q_SCALE, gt=0, description="Q = care_q_scale I6 in (34) (E002-05) [1/s^..]."
    )
    G1: float = Field(pub.G1, description="G1 of (31) [-].")
    G2: float = Field(pub.G2, description="G2 of (31) = 1/(l (1 + mu1)) [s^4/m^2].")
    G3: Vec3 = Field(tuple(pub.G3), description="Diagonal of G3 in (32) [-].")
    G4: float = Field(pub.G4, description="G4 of (32) = -1/(beta1 (1 + mu1)) [-].")
    l: float = Field(pub.L_LOF, gt=0, description="l of (43) [-].")
    mu1: float = Field(pub.MU1, gt=0, description="mu1 of Theorem 2 [-].")
    beta1: float = Field(pub.BETA1, gt=0, description="beta1 of (43) [-].")
    gamma2: float = Field(pub.GAMMA2, gt=0, description="gamma2 of (37) [-].")
    gamma3: float = Field(pub.GAMMA3, gt=0, description="gamma3 of (36) [-].")
    pi_initial: float = Field(1.0, description="pi(-tau) (E002-08 [CHOICE]: 1) [-].")
    v_initial: Vec3 = Field((0.0, 0.0, 0.0), description="v(-tau) [m/s^2].")
    learning_interval: float = Field(
        0.001, gt=0, description="tau of (31)-(32): integer multiple of simulation.dt [s]."
    )
    fault_compensation: bool = Field(
        False, description="COF2TC variant u = K e_y - F_hat (optional variant)."
    )

    @field_validator("K")
    @classmethod
    def _k(cls, v):
        return _matrix(v, (3, 6), "controller.K")


class MetricsSection(StrictModel):
    """Windows of the metrics accumulated inside the scan (every step)."""

    fault_rms_delay: float = Field(
        100.0, ge=0, description="RMS of F - F_hat per axis from onset + this delay [s]."
    )
    position_rms_start: float = Field(
        1600.0, ge=0, description="RMS of ||e_pos|| from this time [s]."
    )
    settle_threshold: float = Field(
        0.01, gt=0, description="|F - F_hat| threshold of the settling-time metric [m/s^2]."
    )
    estimate_start: float = Field(
        10.0, ge=0, description="max ||e_y|| of the observer from this time [s] ..."
    )
    estimate_end: float = Field(
        1500.0, ge=0, description="... up to this time (before the first fault) [s]."
    )
    z_amplitude_start: float = Field(
        2100.0, ge=0, description="max |e_z| tracking error from this time [s]."
    )


class Gui2022Scenario(ScenarioBase):
    orbit: OrbitSection = OrbitSection()
    disturbance: DisturbanceSection = DisturbanceSection()
    faults: FaultSection = FaultSection()
    initial: InitialSection = InitialSection()
    observer: ObserverSection = ObserverSection()
    controller: ControllerSection = ControllerSection()
    metrics: MetricsSection = MetricsSection()

    @model_validator(mode="after")
    def _tau_on_grid(self):
        dt = self.simulation.dt
        try:
            learning_steps(self.observer.learning_interval, dt, "observer.learning_interval")
            learning_steps(self.controller.learning_interval, dt, "controller.learning_interval")
        except LearningIntervalError as exc:
            raise ValueError(str(exc)) from None
        return self
