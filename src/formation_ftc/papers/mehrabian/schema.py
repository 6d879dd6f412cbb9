"""Scenario schema of the ``mehrabian`` method (networked EL attitude control under FDI imperfections).

Defaults are the paper's data (gains, fault, disturbance) and this project's documented choices (docs/errata.md) for what the paper
does not give (graph, nominal inertia, FDI estimate, desired attitude, step). Angles in the file are
in degrees (converted to rad at load), everything else SI.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from formation_ftc.config.base import ExprText, ScenarioBase, StrictModel
from formation_ftc.core import graph as graphs
from formation_ftc.core.dynamics.euler_lagrange import (
    SINGULAR_PITCH_LIMIT_RAD,
    check_away_from_singularity,
)

__all__ = [
    "DEFAULT_EDGES",
    "NOMINAL_INERTIA",
    "FormationSection",
    "InitialSection",
    "DesiredSection",
    "DisturbanceSection",
    "ControllerSection",
    "FaultEntry",
    "IsolationEntry",
    "FDISection",
    "MetricsSection",
    "MehrabianScenario",
]

#: Our choice (the paper is silent): ring 1-2-...-8-1 plus chords 1-5 and 3-7 (the paper's Fig. 1 is not in the text).
DEFAULT_EDGES: list[tuple[int, int]] = [
    (1, 2),
    (2, 3),
    (3, 4),
    (4, 5),
    (5, 6),
    (6, 7),
    (7, 8),
    (8, 1),
    (1, 5),
    (3, 7),
]

#: Our choice (E003-10): the nominal principal inertia diag(20, 18, 15) kg m^2, the default of the truth's
#: formation.nominal_inertia and of the law's model controller.nominal_inertia (J^)
NOMINAL_INERTIA = (20.0, 18.0, 15.0)

_PITCH_LIMIT_DEG = float(np.rad2deg(SINGULAR_PITCH_LIMIT_RAD))
Vec3Expr = tuple[ExprText, ExprText, ExprText]


class FormationSection(StrictModel):
    n_spacecraft: int = Field(8, ge=2, le=64, description="Number m of spacecraft [-].")
    edges: list[tuple[int, int]] = Field(
        default_factory=lambda: list(DEFAULT_EDGES),
        description="Undirected communication links as 1-based spacecraft pairs, unit weights [-]. "
        "Default: ring 1..8 plus chords 1-5, 3-7 (our choice; the paper's Fig. 1 is not given).",
    )
    nominal_inertia: tuple[float, float, float] = Field(
        NOMINAL_INERTIA,
        description="Truth: principal inertia diag(...) about which every spacecraft's true inertia "
        "is drawn [kg m^2] (the law's model is controller.nominal_inertia).",
    )
    inertia_uncertainty: float = Field(
        0.1,
        ge=0.0,
        lt=1.0,
        description="True J = J^ diag(1 + delta), delta ~ U[-u, u]^3 per spacecraft, "
        "drawn from the run seed [-] (paper: +-10 %).",
    )

    @field_validator("nominal_inertia")
    @classmethod
    def _positive(cls, v):
        for k, x in enumerate(v):
            if not x > 0:
                raise ValueError(
                    f"formation.nominal_inertia[{k}] = {x}: principal inertias must be > 0 kg m^2"
                )
        return v

    @model_validator(mode="after")
    def _graph(self):
        m = self.n_spacecraft
        if not self.edges:
            raise ValueError("formation.edges: at least one link is needed")
        for k, (a, b) in enumerate(self.edges):
            if not (1 <= a <= m and 1 <= b <= m):
                raise ValueError(
                    f"formation.edges[{k}] = [{a}, {b}]: spacecraft numbers must be in 1..{m}"
                )
            if a == b:
                raise ValueError(f"formation.edges[{k}] = [{a}, {b}]: self-loops are not allowed")
        A = self.adjacency()
        if not graphs.is_connected_undirected(A):
            import networkx as nx

            comps = [
                sorted(int(i) + 1 for i in c)
                for c in nx.connected_components(graphs.to_networkx(A).to_undirected())
            ]
            raise ValueError(
                f"formation.edges: the communication graph is not connected (components {comps}); the "
                "distributed H-infinity law (8) needs a connected undirected graph (Mehrabian Sec. II-B) "
                "-- an isolated group can never synchronise with the others"
            )
        return self

    def adjacency(self) -> np.ndarray:
        """Symmetric unit-weight adjacency (row = receiver) built with core.graph."""
        return graphs.adjacency(
            self.n_spacecraft, [(a - 1, b - 1) for a, b in self.edges], directed=False
        )


class InitialSection(StrictModel):
    random: bool = Field(
        True,
        description="Draw every Euler angle from U[range] with the run seed (inside the "
        "run, so a campaign varies it through params.seed).",
    )
    attitude_range_deg: tuple[float, float] = Field(
        (0.0, 60.0), description="Range of the random initial Euler angles [deg] (paper: 0..60)."
    )
    attitude_deg: list[tuple[float, float, float]] | None = Field(
        None,
        description="Explicit initial [theta (pitch), phi (roll), psi (yaw)] per spacecraft [deg] "
        "(used when random = false).",
    )
    rate_deg_s: list[tuple[float, float, float]] | None = Field(
        None,
        description="Initial Euler-angle rates per spacecraft [deg/s] (default 0, our choice).",
    )

    @model_validator(mode="after")
    def _check(self):
        lo, hi = self.attitude_range_deg
        if not lo <= hi:
            raise ValueError(
                f"initial.attitude_range_deg = [{lo}, {hi}]: lower bound must be <= upper bound"
            )
        if self.random and max(abs(lo), abs(hi)) >= _PITCH_LIMIT_DEG:
            raise ValueError(
                f"initial.attitude_range_deg = [{lo}, {hi}] deg can draw a pitch at or beyond "
                f"+-{_PITCH_LIMIT_DEG:.0f} deg: the Euler-angle EL model is singular at theta = +-90 deg "
                "(R_bar has 1/cos(theta), E003-08); use a range inside "
                f"(-{_PITCH_LIMIT_DEG:.0f}, {_PITCH_LIMIT_DEG:.0f}) deg"
            )
        if not self.random:
            if self.attitude_deg is None:
                raise ValueError("initial.attitude_deg is required when initial.random = false")
            check_away_from_singularity(
                np.deg2rad(np.asarray(self.attitude_deg, dtype=float)), field="initial.attitude_deg"
            )
        return self


class DesiredSection(StrictModel):
    attitude: Vec3Expr = Field(
        ("0", "0", "0"),
        description="Biased desired attitude e_j(t) = q*(t) + q_j^b per channel [rad], "
        "expressions in t [s] and i (1-based spacecraft); derivatives by autodiff.",
    )


class DisturbanceSection(StrictModel):
    variance: float = Field(
        0.001,
        ge=0.0,
        description="Variance of the Gaussian input disturbance d_j, "
        "i.i.d. per spacecraft/channel, held over each step [(N m)^2].",
    )


class ControllerSection(StrictModel):
    law: Literal["literal", "diffusive"] = Field(
        "literal",
        description="Reading of the garbled law (8): 'literal' first line or 'diffusive' (E003-01).",
    )
    compensation: Literal["sat", "sign", "certainty_equivalence"] = Field(
        "sat",
        description="Gamma of (18): sat(s/phi_b) (Remark 1), sgn(s) as printed, or -u^ (E003-07).",
    )
    gamma: float = Field(0.6, gt=0.0, description="H-infinity level gamma_j [-].")
    alpha: float = Field(
        0.86, description="Synchronisation weight alpha_j, (10) needs 0 < alpha < 1 [-]."
    )
    K: float = Field(20.0, description="K_j = K I_3 [N m s].")
    K_P: float = Field(0.16, description="Proportional gain K-bar_j = K_P I_3 (E003-03) [1/s].")
    K_I: float = Field(
        0.001, description="Integral gain K-double-bar_j = K_I I_3 (E003-03) [1/s^2]."
    )
    sigma: float = Field(
        0.5, gt=0.0, description="Adaptation gain Sigma-bar_j = sigma I_3 [N m / (rad)]."
    )
    e_gain: float = Field(
        1.0, gt=0.0, description="Estimate pull E-bar_j = e I_3 towards the FDI estimate [1/s]."
    )
    boundary_layer: float = Field(
        0.01, gt=0.0, description="Width phi_b of sat(s/phi_b) [rad/s] (our choice)."
    )
    nominal_inertia: tuple[float, float, float] = Field(
        NOMINAL_INERTIA,
        description="Principal inertia J^ = diag(...) of the law's model, known on board [kg m^2], "
        "each > 0 (default 20, 18, 15 kg m^2, a stated nominal value: never the "
        "truth's formation.nominal_inertia).",
    )

    @field_validator("nominal_inertia")
    @classmethod
    def _positive(cls, v):
        for k, x in enumerate(v):
            if not x > 0:
                raise ValueError(
                    f"controller.nominal_inertia[{k}] = {x}: principal inertias must be > 0 kg m^2"
                )
        return v


class FaultEntry(StrictModel):
    spacecraft: int = Field(ge=1, description="Faulty spacecraft (1-based) [-].")
    channel: int = Field(
        ge=1, le=3, description="Faulty input channel 1 = pitch, 2 = roll, 3 = yaw [-]."
    )
    torque: ExprText = Field(
        description="Additive fault u_bar(t) while active, expression in t [s] [N m]."
    )
    start: float = Field(
        ge=0.0, description="Fault start (inclusive, snapped to the step grid) [s]."
    )
    end: float = Field(description="Fault end (inclusive, snapped to the step grid) [s].")

    @model_validator(mode="after")
    def _order(self):
        if not self.end >= self.start:
            raise ValueError(f"faults: end = {self.end} s must be >= start = {self.start} s")
        return self


class IsolationEntry(StrictModel):
    spacecraft: int = Field(ge=1, description="True faulty spacecraft (1-based) [-].")
    channel: int = Field(ge=1, le=3, description="True faulty channel [-].")
    reported_spacecraft: int = Field(ge=1, description="Spacecraft the FDI blames (1-based) [-].")
    reported_channel: int = Field(ge=1, le=3, description="Channel the FDI blames [-].")


class FDISection(StrictModel):
    enabled: bool = Field(
        True, description="False: no FDI and no reconfiguration at all (Gamma = 0)."
    )
    detected: bool = Field(True, description="False models a missed detection (Case 1).")
    delay: float = Field(
        5.0, ge=0.0, description="Detection latency; the estimate also lags by it [s]."
    )
    scale: float = Field(
        1.0, description="Identification scale error: u* = scale u_bar(t - delay) + bias [-]."
    )
    bias: float = Field(
        -0.1, description="Identification bias while the fault is seen [N m] (our choice: -0.1)."
    )
    noise_std: float = Field(
        0.0, ge=0.0, description="Std of a per-step Gaussian identification noise [N m]."
    )
    isolation: list[IsolationEntry] = Field(
        default_factory=list,
        description="Isolation errors (Case 2): report a true fault elsewhere.",
    )


class MetricsSection(StrictModel):
    """Windows are clipped to the horizon; a window that starts after the horizon yields no metrics."""

    fault_window: tuple[float, float] = Field(
        (40.0, 240.0), description="Window of the fault-window metrics [s]."
    )
    assessment_window: tuple[float, float] = Field(
        (45.0, 240.0),
        description="Window of the reproduction's comparisons (from the reconfiguration) [s].",
    )

    @model_validator(mode="after")
    def _order(self):
        for name in ("fault_window", "assessment_window"):
            a, b = getattr(self, name)
            if not 0 <= a < b:
                raise ValueError(f"metrics.{name} = [{a}, {b}]: need 0 <= start < end [s]")
        return self


class MehrabianScenario(ScenarioBase):
    formation: FormationSection = FormationSection()
    initial: InitialSection = InitialSection()
    desired: DesiredSection = DesiredSection()
    disturbance: DisturbanceSection = DisturbanceSection()
    controller: ControllerSection = ControllerSection()
    faults: list[FaultEntry] = Field(
        default_factory=list, description="Additive actuator faults (2)."
    )
    fdi: FDISection = FDISection()
    metrics: MetricsSection = MetricsSection()

    @model_validator(mode="after")
    def _cross(self):
        m = self.formation.n_spacecraft
        for k, f in enumerate(self.faults):
            if f.spacecraft > m:
                raise ValueError(f"faults[{k}].spacecraft = {f.spacecraft}: must be in 1..{m}")
        faulty = {(f.spacecraft, f.channel) for f in self.faults}
        for k, e in enumerate(self.fdi.isolation):
            if e.spacecraft > m or e.reported_spacecraft > m:
                raise ValueError(f"fdi.isolation[{k}]: spacecraft numbers must be in 1..{m}")
            if (e.spacecraft, e.channel) not in faulty:
                raise ValueError(
                    f"fdi.isolation[{k}]: spacecraft {e.spacecraft} channel {e.channel} has no fault "
                    f"(faulty channels: {sorted(faulty)})"
                )
        if self.initial.attitude_deg is not None and len(self.initial.attitude_deg) != m:
            raise ValueError(
                f"initial.attitude_deg: {len(self.initial.attitude_deg)} rows for {m} spacecraft"
            )
        if self.initial.rate_deg_s is not None and len(self.initial.rate_deg_s) != m:
            raise ValueError(
                f"initial.rate_deg_s: {len(self.initial.rate_deg_s)} rows for {m} spacecraft"
            )
        return self
