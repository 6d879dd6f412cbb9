"""Scenario schema of method ``li2020`` (Li et al. 2020).

Every parameter of the paper's Sec. IV is a field; where the paper is silent (adaptation gains,
horizon, step) the defaults are our choices (errata E000-12, E000-16). Time functions (faults,
disturbances, delays) are expression strings (:mod:`formation_ftc.core.expressions`) in ``t`` [s] and
``i`` (1-based spacecraft number); delays also see ``j`` (the sender).
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from formation_ftc.config.base import ExprText, ScenarioBase, StrictModel, expression_validator
from formation_ftc.config.sections import SpacecraftSection
from formation_ftc.core.graph import GraphError, validate_adjacency
from formation_ftc.core.orbit import MU_EARTH

__all__ = [
    "Li2020Scenario",
    "OrbitSection",
    "SpacecraftSection",
    "FormationSection",
    "NetworkSection",
    "ControllerSection",
    "SirFtcSection",
    "FaultSection",
    "DisturbanceSection",
    "DelayExpr",
    "ALPHA3_LITERAL",
    "ALPHA3_CORRECTED",
]

#: Delay T_ij(t) [s]: expression in t [s], i (receiver) and j (sender), both 1-based.
DelayExpr = Annotated[str, expression_validator(("t", "i", "j"))]
Vec3Expr = tuple[ExprText, ExprText, ExprText]

#: alpha_i3 as printed (onset 20 s, exponent with (t - 10)) and with the E000-06 fix ((t - 20)).
ALPHA3_LITERAL = "where(t >= 20, 1 - 0.05*(i+2)*exp(-0.2*(t-10)), 1)"
ALPHA3_CORRECTED = "where(t >= 20, 1 - 0.05*(i+2)*exp(-0.2*(t-20)), 1)"

FloatOrList = float | list[float]


def _per_spacecraft(value: FloatOrList, n: int, field: str) -> list[float]:
    if isinstance(value, list):
        if len(value) != n:
            raise ValueError(
                f"{field}: {len(value)} values for {n} spacecraft (give one value or {n})"
            )
        return [float(v) for v in value]
    return [float(value)] * n


class OrbitSection(StrictModel):
    """Reference (virtual chief) orbit, Sec. IV-A."""

    semi_major_axis: float = Field(7000e3, gt=0, description="a_c [m].")
    eccentricity: float = Field(0.02, ge=0, lt=1, description="e_c [-].")
    true_anomaly0: float = Field(0.0, description="theta_c(0) [rad].")
    mu: float = Field(MU_EARTH, gt=0, description="Earth gravitational parameter [m^3/s^2].")
    raan: float = Field(
        math.pi / 4, description="Omega_c [rad] (does not enter the relative dynamics)."
    )
    inclination: float = Field(
        math.pi / 6, description="i_c [rad] (does not enter the relative dynamics)."
    )
    arg_perigee: float = Field(
        math.pi / 6, description="omega_c [rad] (does not enter the relative dynamics)."
    )
    reference_mass: float = Field(200.0, gt=0, description="m_c [kg] (virtual reference; unused).")

    @property
    def semi_latus_rectum(self) -> float:
        return self.semi_major_axis * (1.0 - self.eccentricity**2)

    @property
    def mean_motion(self) -> float:
        """n_c = sqrt(mu / a^3) [rad/s] (E000-09)."""
        return math.sqrt(self.mu / self.semi_major_axis**3)

    @property
    def period(self) -> float:
        """T_c = 2 pi / n_c [s]."""
        return 2 * math.pi / self.mean_motion


class FormationSection(StrictModel):
    """Desired rotating, expanding formation and moving centre (Sec. IV-A)."""

    radius: float = Field(
        500.0,
        gt=0,
        description="R of rho_bar_iF = R[cos(phi_i)/2, -sin(phi_i), sqrt(3)/2 cos(phi_i)] [m].",
    )
    phase: list[float] = Field(
        [0.0, math.pi / 2, math.pi, 3 * math.pi / 2],
        description="phi_i of each spacecraft on the formation circle [rad].",
    )
    rotation: float = Field(
        math.pi / 6, description="Final rotation angle of phi_bar(t) about y [rad]."
    )
    growth: float = Field(
        0.6, gt=-1, description="lambda(t) = 1 + growth g(t): final relative size change [-]."
    )
    centre_offset: tuple[float, float, float] = Field(
        (300.0, 0.0, 0.0), description="rho_o^d(inf) [m]."
    )
    chi: float | None = Field(
        None,
        gt=0,
        description="chi of g(t) = 1 - exp(-t^2/(2 chi)) [s^2]; default "
        "-(completion_fraction T_c)^2 / (2 ln completion_residual) (E000-09).",
    )
    completion_fraction: float = Field(
        0.5, gt=0, description="Fraction of T_c at which g reaches 1 - residual [-]."
    )
    completion_residual: float = Field(1e-6, gt=0, lt=1, description="1 - g at completion [-].")


class NetworkSection(StrictModel):
    adjacency: list[list[float]] = Field(
        description="Weighted adjacency C, row i = receiver (c_ij > 0: i receives from j) [-]."
    )
    delays: list[list[DelayExpr]] | None = Field(
        None,
        description="T_ij(t) [s], row i = receiver, column j = sender; expressions in t, i, j. "
        "Diagonal ignored. Used only by controller.law = 'thm2'.",
    )

    @field_validator("adjacency")
    @classmethod
    def _adjacency(cls, v):
        try:
            validate_adjacency(v, field="network.adjacency")
        except GraphError as exc:
            raise ValueError(str(exc)) from None
        return v


class ControllerSection(StrictModel):
    """Thm 1 (eqs. (23)-(27)), Thm 2 (eqs. (41)-(45)) or the SIR-FTC baseline (Sec. IV-D)."""

    law: Literal["thm1", "thm2", "sir-ftc"] = Field(description="Control law.")
    k: FloatOrList = Field(
        0.2, description="k_i of s_i = e_i2 + k_i e_i1 (eq. (6)) [1/s], > 0 (Lemma 2)."
    )
    lam: FloatOrList = Field(20.0, description="lambda_i [kg/s] (Thm 1: 20, Thm 2: 15).")
    gamma: FloatOrList = Field(
        0.1,
        description="gamma_i, beta_hat adaptation gain [s/(kg m^2)] (not in the paper: our choice, E000-12).",
    )
    eta: FloatOrList = Field(
        1.0,
        description="eta_i, m_hat adaptation gain [kg s/m^2] (not in the paper: our choice, E000-12).",
    )
    mu: FloatOrList = Field(
        1.0,
        description="mu_i, d_hat adaptation gain [N s/m] (not in the paper: our choice, E000-12).",
    )
    upsilon: FloatOrList = Field(
        0.01,
        description="upsilon_i, d_hat leakage gain [1/(N s)] per unit sigma (not in the paper: our choice, E000-12).",
    )
    m_hat0: FloatOrList = Field(100.0, description="m_hat_i(0) [kg].")
    beta_hat0: FloatOrList = Field(1.0, description="beta_hat_i(0) [-].")
    d_hat0: FloatOrList = Field(0.001, description="d_hat_i(0) [N], > 0.")
    sigma_form: Literal["exponential", "inverse_square"] = Field(
        "exponential",
        description="sigma_i(t): 'exponential' exp(-a t) (eq. (13)) or "
        "'inverse_square' 1/(a (t + t0)^2) (eq. (14), shifted by t0).",
    )
    sigma_a: FloatOrList = Field(
        0.001, description="a_i of sigma_i(t) [1/s] (exponential) or [1/s^2] (inverse square)."
    )
    sigma_t0: float = Field(1.0, gt=0, description="t0 of the inverse-square sigma [s].")
    dhat_sign_literal: bool = Field(
        False,
        description="Use the printed sign of the d_hat tanh term (+ in eq. (24), - in eq. (42)) "
        "instead of + in both (E000-04).",
    )

    @field_validator("d_hat0", "sigma_a", "m_hat0")
    @classmethod
    def _positive(cls, v, info):
        vals = v if isinstance(v, list) else [v]
        if any(not x > 0 for x in vals):
            raise ValueError(f"controller.{info.field_name} must be > 0, got {v}")
        return v


class SirFtcSection(StrictModel):
    """SIR-FTC baseline parameters (Sec. IV-D; E000-16 renames mu -> mu_s)."""

    k0: float = Field(20.0, gt=0, description="k0 [kg/s].")
    phi: float = Field(1.0, gt=0, description="Phi [-].")
    sigma1: float = Field(1.0, gt=0, description="sigma_1 [1/s].")
    sigma2: float = Field(10.0, gt=0, description="sigma_2 [kg/m].")
    mu_s: float = Field(1.0, gt=0, description="mu of eps = mu/(1 + Phi) [m/s].")
    b_hat0: float = Field(10.0, description="b_hat_i(0) [N].")


class FaultSection(StrictModel):
    """Actuator faults F_i = Gamma_i(t) f_i + delta_i(t), eq. (5)."""

    effectiveness: Vec3Expr = Field(
        (
            "where(t >= 10, 1 - 0.1*(i+1)*exp(-(t-10)), 1)",
            "where(t >= 15, 1 - 0.1*exp(-0.5*i*(t-15)), 1)",
            ALPHA3_CORRECTED,
        ),
        description="alpha_i1..alpha_i3(t) in (0, 1] [-]; onsets use the t >= t0 branch (E000-06).",
    )
    alpha3_literal: bool = Field(
        False, description="Replace alpha_i3 by the printed form with exp(-0.2 (t - 10)) (E000-06)."
    )
    profile: Literal["expressions", "step"] = Field(
        "expressions",
        description="'expressions': Gamma_i(t) from faults.effectiveness; 'step': "
        "alpha_ij = faults.step_effectiveness[i][j] from faults.step_onset[i][j] on (numeric, so Monte "
        "Carlo campaigns vary them without recompiling).",
    )
    step_effectiveness: list[tuple[float, float, float]] | None = Field(
        None,
        description="Step profile: effectiveness after onset per spacecraft and axis, in (0, 1] [-].",
    )
    step_onset: list[tuple[float, float, float]] | None = Field(
        None,
        description="Step profile: onset time per spacecraft and axis, >= 0 [s] (snapped to the step grid).",
    )
    additive: Vec3Expr = Field(
        (
            "0.1*((i+1)*cos(0.1*t) + 2*exp(-0.2*t))",
            "0.1*(i*sin(0.2*t) + exp(-0.3*t))",
            "0.1*((2*i-1)*cos(0.3*t) - exp(-0.4*t))",
        ),
        description="delta_i(t) [N].",
    )

    @model_validator(mode="after")
    def _literal_flag(self):
        if self.alpha3_literal and self.effectiveness[2] not in (ALPHA3_CORRECTED, ALPHA3_LITERAL):
            raise ValueError(
                "faults.alpha3_literal = true replaces faults.effectiveness[2]; it cannot be "
                "combined with a user-defined alpha_i3 expression"
            )
        return self

    def effectiveness_texts(self) -> tuple[str, str, str]:
        e = self.effectiveness
        return (e[0], e[1], ALPHA3_LITERAL if self.alpha3_literal else e[2])


class DisturbanceSection(StrictModel):
    force: Vec3Expr = Field(
        (
            "0.05*((i+1)*cos(0.1*t) + 2*i*sin(0.2*t))",
            "0.05*(2*i*cos(0.2*t) + 3*i)",
            "0.05*((i-3)*sin(0.1*t) - 2*i)",
        ),
        description="External disturbance h_i(t) [N] (printed as d_i; E000-11).",
    )


class Li2020Scenario(ScenarioBase):
    orbit: OrbitSection = OrbitSection()
    spacecraft: SpacecraftSection
    formation: FormationSection = FormationSection()
    network: NetworkSection
    controller: ControllerSection
    sir_ftc: SirFtcSection = SirFtcSection()
    faults: FaultSection = FaultSection()
    disturbance: DisturbanceSection = DisturbanceSection()

    @model_validator(mode="after")
    def _cross(self):
        n = self.spacecraft.count
        try:
            validate_adjacency(self.network.adjacency, n, field="network.adjacency")
        except GraphError as exc:
            raise ValueError(str(exc)) from None
        if len(self.formation.phase) != n:
            raise ValueError(
                f"formation.phase: {len(self.formation.phase)} values for {n} spacecraft"
            )
        f = self.faults
        if f.profile == "step":
            for name, lo, hi, unit in (
                ("step_effectiveness", 0.0, 1.0, "-"),
                ("step_onset", 0.0, None, "s"),
            ):
                rows = getattr(f, name)
                if rows is None or len(rows) != n:
                    got = "missing" if rows is None else f"{len(rows)} rows"
                    raise ValueError(
                        f"faults.{name}: {got}; faults.profile = 'step' needs {n} rows of 3 values"
                    )
                for i, row in enumerate(rows):
                    for j, v in enumerate(row):
                        ok = (v > lo and v <= hi) if name == "step_effectiveness" else v >= lo
                        if not ok:
                            rng = "(0, 1]" if name == "step_effectiveness" else ">= 0"
                            raise ValueError(
                                f"faults.{name}[{i}][{j}] = {v}: must be {rng} [{unit}]"
                            )
        c = self.controller
        for name in (
            "k",
            "lam",
            "gamma",
            "eta",
            "mu",
            "upsilon",
            "m_hat0",
            "beta_hat0",
            "d_hat0",
            "sigma_a",
        ):
            _per_spacecraft(getattr(c, name), n, f"controller.{name}")
        if any(v <= 0 for v in _per_spacecraft(c.k, n, "controller.k")):
            raise ValueError("controller.k: k_i must be > 0 (Lemma 2)")
        if c.law == "thm2":
            d = self.network.delays
            if d is None:
                raise ValueError("network.delays: required for controller.law = 'thm2'")
            if len(d) != n or any(len(r) != n for r in d):
                raise ValueError(f"network.delays: must be an {n}x{n} matrix of expressions")
            from formation_ftc.papers.li2020.conditions import DelayError, validate_delays

            try:
                validate_delays(self)
            except DelayError as exc:
                raise ValueError(str(exc)) from None
        return self

    def per_spacecraft(self, name: str) -> np.ndarray:
        """controller.<name> broadcast to (N,)."""
        return np.asarray(
            _per_spacecraft(
                getattr(self.controller, name), self.spacecraft.count, f"controller.{name}"
            )
        )
