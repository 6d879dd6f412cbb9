"""Scenario schema of the ``azizi2009`` method (Azizi & Khorasani 2009).

Sections beyond ``[scenario]``/``[simulation]``: ``[formation]``, ``[controller]``, ``[allocation]``,
``[fault]``, ``[disturbance]``, ``[noise]``, ``[supervisor]``. Defaults are the
baseline of the reproduction (four satellites, 80 % gain on satellite 2, x; b_hat = 0.88).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, field_validator, model_validator

from formation_ftc.config.base import ExprText, ScenarioBase, StrictModel

__all__ = [
    "FormationSection",
    "ControllerSection",
    "AllocationSection",
    "FaultSection",
    "DisturbanceSection",
    "NoiseSection",
    "SupervisorSection",
    "Azizi2009Scenario",
]


class FormationSection(StrictModel):
    n_satellites: int = Field(
        4, ge=3, le=16, description="Number of satellites on the output chain [-]."
    )
    n_axes: int = Field(
        3, ge=1, le=3, description="Simulated axes: 1 = x only, 2 = x, y, 3 = x, y, z [-]."
    )
    side: float = Field(
        200.0, gt=0, description="Side of the desired regular polygon (square for 4) [m]."
    )
    omega: float = Field(
        0.1, description="Rotation rate of the desired formation, counter-clockwise in xy [rad/s]."
    )
    b: list[float] = Field(
        [1.0, 1.0, 1.0, 1.0], description="Nominal actuator gains b_i (all axes) [-]."
    )
    initial_offset_x: list[float] | None = Field(
        None,
        description="Initial x-position offsets from the desired trajectory per satellite [m] (default 0).",
    )

    @field_validator("b")
    @classmethod
    def _b_positive(cls, v: list[float]) -> list[float]:
        if any(not x > 0 for x in v):
            raise ValueError(f"formation.b (actuator gains) must all be > 0, got {v}")
        return v

    @model_validator(mode="after")
    def _sizes(self) -> FormationSection:
        if len(self.b) != self.n_satellites:
            raise ValueError(
                f"formation.b has {len(self.b)} entries; formation.n_satellites = {self.n_satellites}"
            )
        if self.initial_offset_x is not None and len(self.initial_offset_x) != self.n_satellites:
            raise ValueError(
                f"formation.initial_offset_x has {len(self.initial_offset_x)} entries; "
                f"formation.n_satellites = {self.n_satellites}"
            )
        return self


class ControllerSection(StrictModel):
    lambda0: float = Field(
        2.0, gt=0, description="Position gain lambda_0 of p_ij (Azizi2009 Sec. II) [1/s^2]."
    )
    lambda1: float = Field(3.0, gt=0, description="Velocity gain lambda_1 of p_ij [1/s].")
    sampling: Literal["zoh", "continuous"] = Field(
        "zoh",
        description="'zoh': control computed at t_k and held over the step (exact double-integrator "
        "update); 'continuous': control re-evaluated at the RK4 stages "
        "(continuous-time loop, used to check the reduced model (7)).",
    )


class AllocationSection(StrictModel):
    alpha: list[float] = Field(
        [1.0, 1.0, 1.0, 1.0], description="LLFR cost weights alpha_i of eq. (3) [-]."
    )

    @field_validator("alpha")
    @classmethod
    def _alpha_positive(cls, v: list[float]) -> list[float]:
        if any(not x > 0 for x in v):
            raise ValueError(
                f"allocation.alpha must all be > 0 (weights of sum alpha_i u_i^2 / 2), got {v}"
            )
        return v


class FaultSection(StrictModel):
    enabled: bool = Field(True, description="Loss-of-effectiveness fault on one actuator [-].")
    satellite: int = Field(2, ge=1, description="Faulty satellite (1-based) [-].")
    axis: Literal["x", "y", "z"] = Field("x", description="Faulty actuator axis [-].")
    effectiveness: float = Field(
        0.8, gt=0, le=1, description="True gain factor b_k / b_k,nominal after the fault [-]."
    )
    onset: float = Field(0.0, ge=0, description="Fault onset time (snapped to the step grid) [s].")
    estimate: float = Field(
        0.88, description="LLFR estimate b_hat_k of the faulty gain [-] (must be > 0)."
    )
    estimated_at: float = Field(
        0.0, ge=0, description="Time the fault estimate reaches the HL supervisor [s]."
    )
    b_eps: float = Field(0.08, gt=0, description="Known bound B_eps on |b_hat_k - b_k| [-].")

    @field_validator("estimate")
    @classmethod
    def _estimate_positive(cls, v: float) -> float:
        if not v > 0:
            raise ValueError(
                f"fault.estimate (b_hat) must be > 0: b_hat = 0 is a dead actuator and makes "
                f"J_aug of eq. (3) undefined; got {v}"
            )
        return v


class DisturbanceSection(StrictModel):
    acceleration: ExprText = Field(
        "1e-5*cos(0.01*t + i)",
        description="Solar-pressure-like disturbance d_i(t) on every axis, expression in t [s] and i [m/s^2] (E004-10).",
    )
    bound: float = Field(
        2e-5, ge=0, description="Bound B_ext on the differential disturbance |d_j - d_i| [m/s^2]."
    )


class NoiseSection(StrictModel):
    sigma_position: float = Field(
        0.0, ge=0, description="Std of Gaussian noise on measured e_ij [m] (E004-09)."
    )
    sigma_velocity: float = Field(
        0.0, ge=0, description="Std of Gaussian noise on measured de_ij/dt [m/s]."
    )


class SupervisorSection(StrictModel):
    flfr: bool = Field(
        False, description="Let the HL supervisor activate FLFR on a violation of e_s [-]."
    )
    e_s: float = Field(0.03, gt=0, description="Mission error bound e_s [m].")
    violation_probability: float = Field(
        0.0, description="pi of eq. (11); 0 <= pi < 1, pi = 0 is the deterministic design (9) [-]."
    )
    alpha_flfr: float | None = Field(
        None,
        description="FLFR weight alpha_k; None = designed by eq. (11) with violation_probability [-].",
    )
    confirm_time: float = Field(
        0.0, ge=0, description="Violation must persist this long before FLFR [s]."
    )
    monitor_start: float = Field(0.0, ge=0, description="Start of the monitoring window [s].")
    settle_time: float = Field(
        20.0, ge=0, description="Metric max_err_after_flfr starts this long after the switch [s]."
    )
    design_dt: float = Field(1e-3, gt=0, description="Step of the H_i convolution simulation [s].")
    alpha_reference: float = Field(
        1.0, gt=0, description="alpha_k at which A_clp is evaluated for H_i [-]."
    )

    @field_validator("violation_probability")
    @classmethod
    def _pi_range(cls, v: float) -> float:
        if not (0.0 <= v < 1.0):
            raise ValueError(
                f"supervisor.violation_probability must satisfy 0 <= pi < 1 (pi = 0 is the "
                f"deterministic design of eq. (9)), got {v}"
            )
        return v

    @field_validator("alpha_flfr")
    @classmethod
    def _alpha_positive(cls, v: float | None) -> float | None:
        if v is not None and not v > 0:
            raise ValueError(f"supervisor.alpha_flfr must be > 0, got {v}")
        return v


class Azizi2009Scenario(ScenarioBase):
    formation: FormationSection = FormationSection()
    controller: ControllerSection = ControllerSection()
    allocation: AllocationSection = AllocationSection()
    fault: FaultSection = FaultSection()
    disturbance: DisturbanceSection = DisturbanceSection()
    noise: NoiseSection = NoiseSection()
    supervisor: SupervisorSection = SupervisorSection()

    @model_validator(mode="after")
    def _consistency(self) -> Azizi2009Scenario:
        n = self.formation.n_satellites
        if len(self.allocation.alpha) != n:
            raise ValueError(
                f"allocation.alpha has {len(self.allocation.alpha)} entries; "
                f"formation.n_satellites = {n}"
            )
        if self.fault.satellite > n:
            raise ValueError(f"fault.satellite = {self.fault.satellite} must be in 1..{n}")
        if "xyz".index(self.fault.axis) >= self.formation.n_axes:
            raise ValueError(
                f"fault.axis = '{self.fault.axis}' is not simulated (formation.n_axes = "
                f"{self.formation.n_axes})"
            )
        if self.supervisor.flfr and self.fault.enabled and not (1 < self.fault.satellite < n):
            raise ValueError(
                f"supervisor.flfr needs an interior faulty satellite (2..{n - 1}); "
                f"fault.satellite = {self.fault.satellite}"
            )
        if (
            self.supervisor.flfr
            and self.supervisor.alpha_flfr is None
            and (n != 4 or self.fault.satellite != 2)
        ):
            raise ValueError(
                "supervisor.alpha_flfr = None (analytic design, reduced model (7)) is implemented "
                "for formation.n_satellites = 4 and fault.satellite = 2; give supervisor.alpha_flfr"
            )
        return self
