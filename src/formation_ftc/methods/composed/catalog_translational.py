"""Catalog: translational plants, reference orbits, relative-state sensors, graph networks, formation
laws and thruster faults for composed scenarios."""

from __future__ import annotations

import math
from typing import Literal, cast

import numpy as np
from pydantic import Field, model_validator

from formation_ftc.components.actuators.expression_faults import ExpressionFaultActuator
from formation_ftc.components.actuators.thruster_bias import ThrusterBiasFaultActuator
from formation_ftc.components.controllers.desired_formation import RotatingFormation
from formation_ftc.components.controllers.li2020_adaptive import Li2020AdaptiveController
from formation_ftc.components.controllers.pd_formation import PdFormationController
from formation_ftc.components.controllers.sir_ftc import SirFtcController
from formation_ftc.components.networks.weighted_graph import (
    DelayedGraphNetwork,
    GraphNetwork,
    graph_edges,
)
from formation_ftc.components.plants.clohessy_wiltshire import ClohessyWiltshirePlant
from formation_ftc.components.plants.relative_lvlh import RelativeLvlhPlant
from formation_ftc.components.references.keplerian import KeplerianReference
from formation_ftc.components.sensors.exact_relative_state import ExactRelativeStateSensors
from formation_ftc.components.sensors.relative_state import RelativeStateSensors
from formation_ftc.config.base import ExprText, StrictModel
from formation_ftc.core.history import required_capacity
from formation_ftc.core.orbit import MU_EARTH
from formation_ftc.core.rotating_formation import chi_from_period, formation_offsets
from formation_ftc.methods.composed import (
    BuildContext,
    per_spacecraft,
    register_component_type,
    require_slot,
)
from formation_ftc.sim.components import as_float

Vec3 = tuple[float, float, float]
Vec3Expr = tuple[ExprText, ExprText, ExprText]


_per_spacecraft = per_spacecraft

#: the PD law's nominal on-board mass when a scenario states none [kg] (``controller.nominal_mass``)
PD_NOMINAL_MASS = 100.0


def _per_axis(value, n: int, field: str) -> np.ndarray:
    """A number, 3 values (per axis, every spacecraft) or N x 3 values -> (N, 3)."""
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        return np.full((n, 3), float(arr))
    if arr.shape == (3,):
        return np.broadcast_to(arr, (n, 3)).copy()
    if arr.shape != (n, 3):
        raise ValueError(f"{field}: shape {arr.shape}, expected a number, 3 values or {n} x 3")
    return arr


# ----------------------------------------------------------------------------------------- plants
class _PointMassSection(StrictModel):
    mass: list[float] = Field(description="True mass of each spacecraft [kg], > 0.")
    initial_position: list[Vec3] = Field(description="Initial LVLH position per spacecraft [m].")
    initial_velocity: list[Vec3] | None = Field(
        None, description="Initial LVLH velocity per spacecraft [m/s] (default 0)."
    )
    disturbance_force: Vec3Expr = Field(
        ("0", "0", "0"), description="External force per axis, expressions in t [s], i [N]."
    )

    @model_validator(mode="after")
    def _sizes(self):
        n = len(self.mass)
        if n < 1 or any(not (m > 0 and math.isfinite(m)) for m in self.mass):
            raise ValueError("mass: at least one spacecraft, every mass finite and > 0 kg")
        if len(self.initial_position) != n:
            raise ValueError(
                f"initial_position: {len(self.initial_position)} rows for {n} spacecraft"
            )
        if self.initial_velocity is not None and len(self.initial_velocity) != n:
            raise ValueError(
                f"initial_velocity: {len(self.initial_velocity)} rows for {n} spacecraft"
            )
        return self

    @property
    def count(self) -> int:
        return len(self.mass)

    def q0(self) -> np.ndarray:
        v0 = (
            np.zeros((self.count, 3))
            if self.initial_velocity is None
            else np.asarray(self.initial_velocity)
        )
        return np.hstack([np.asarray(self.initial_position, float), v0])


class CwPlantSection(_PointMassSection):
    semi_major_axis: float = Field(gt=0, description="Radius of the circular reference orbit [m].")
    mu: float = Field(MU_EARTH, gt=0, description="Gravitational parameter [m^3/s^2].")
    process_noise_std: float = Field(0.0, ge=0, description="Std of a per-step Gaussian force [N].")

    @property
    def mean_motion(self) -> float:
        return math.sqrt(self.mu / self.semi_major_axis**3)


def _cw_plant(sec: CwPlantSection, ctx: BuildContext):
    return ClohessyWiltshirePlant(
        mean_motion=as_float(sec.mean_motion),
        mass=as_float(sec.mass),
        initial_state_lvlh=as_float(sec.q0()),
        process_noise_std=as_float(sec.process_noise_std),
        disturbance_force=sec.disturbance_force,
    )


class RelativeLvlhSection(_PointMassSection):
    mu: float = Field(MU_EARTH, gt=0, description="Gravitational parameter [m^3/s^2].")


def _relative_lvlh_plant(sec: RelativeLvlhSection, ctx: BuildContext):
    return RelativeLvlhPlant(
        mass=as_float(sec.mass),
        initial_state_lvlh=as_float(sec.q0()),
        mu=as_float(sec.mu),
        disturbance_force=sec.disturbance_force,
    )


register_component_type(
    "plant",
    "clohessy-wiltshire",
    CwPlantSection,
    _cw_plant,
    "linear Clohessy-Wiltshire relative motion about a circular orbit (point masses)",
)
register_component_type(
    "plant",
    "relative-lvlh",
    RelativeLvlhSection,
    _relative_lvlh_plant,
    "nonlinear relative motion about an elliptic reference orbit (needs [reference])",
)


# ------------------------------------------------------------------------------------- references
class KeplerianSection(StrictModel):
    semi_major_axis: float = Field(gt=0, description="Semi-major axis of the reference orbit [m].")
    eccentricity: float = Field(0.0, ge=0, lt=1, description="Eccentricity [-].")
    true_anomaly0: float = Field(0.0, description="True anomaly at t = 0 [rad].")
    mu: float = Field(MU_EARTH, gt=0, description="Gravitational parameter [m^3/s^2].")


def _keplerian(sec: KeplerianSection, ctx: BuildContext):
    p = sec.semi_major_axis * (1.0 - sec.eccentricity**2)
    return KeplerianReference(
        semi_latus_rectum=as_float(p),
        eccentricity=as_float(sec.eccentricity),
        mu=as_float(sec.mu),
        true_anomaly0=as_float(sec.true_anomaly0),
    )


register_component_type(
    "reference",
    "keplerian",
    KeplerianSection,
    _keplerian,
    "Keplerian reference orbit (virtual chief); eccentricity 0 gives a circular orbit",
)


# ----------------------------------------------------------------------------------------- sensors
class RelativeStateSection(StrictModel):
    position_noise_std: float = Field(0.0, ge=0, description="Std of the position noise [m].")
    velocity_noise_std: float = Field(0.0, ge=0, description="Std of the velocity noise [m/s].")


def _relative_state(sec: RelativeStateSection, ctx: BuildContext):
    if sec.position_noise_std == 0 and sec.velocity_noise_std == 0:
        return ExactRelativeStateSensors(count=ctx.count)
    return RelativeStateSensors(
        count=ctx.count,
        position_noise_std=as_float(sec.position_noise_std),
        velocity_noise_std=as_float(sec.velocity_noise_std),
    )


register_component_type(
    "sensors",
    "relative-state",
    RelativeStateSection,
    _relative_state,
    "relative position and velocity with Gaussian noise held over each step",
)


# ---------------------------------------------------------------------------------------- networks
class GraphSection(StrictModel):
    adjacency: list[list[float]] = Field(
        description="c_ij >= 0: spacecraft i receives from j (N x N) [-]."
    )

    @model_validator(mode="after")
    def _square(self):
        n = len(self.adjacency)
        if any(len(r) != n for r in self.adjacency):
            raise ValueError("adjacency: must be square (N x N)")
        if any(not (c >= 0 and math.isfinite(c)) for r in self.adjacency for c in r):
            raise ValueError("adjacency: entries must be finite and >= 0")
        return self


class DelayedGraphSection(GraphSection):
    delays: list[list[ExprText]] = Field(
        description="T_ij(t) per link, expressions in t, i, j [s] (N x N); >= 0."
    )
    max_delay: float = Field(
        gt=0, description="Largest delay on any used link [s] (sizes the history buffer)."
    )


def _graph(sec: GraphSection, ctx: BuildContext):
    return GraphNetwork(weights=as_float(sec.adjacency))


def _delayed_graph(sec: DelayedGraphSection, ctx: BuildContext):
    n = len(sec.adjacency)
    if len(sec.delays) != n or any(len(r) != n for r in sec.delays):
        raise ValueError(f"network.delays: must be {n} x {n} like network.adjacency")
    edges = graph_edges(sec.adjacency)
    return DelayedGraphNetwork(
        weights=as_float(sec.adjacency),
        delays=tuple(tuple(str(x) for x in r) for r in sec.delays),
        edges=edges,
        capacity=required_capacity(sec.max_delay, ctx.dt) + 1,
        dt=ctx.dt,
    )


register_component_type(
    "network",
    "graph",
    GraphSection,
    _graph,
    "instantaneous exchange over a weighted directed graph",
)
register_component_type(
    "network",
    "delayed-graph",
    DelayedGraphSection,
    _delayed_graph,
    "weighted directed graph with time-varying delays (history buffer, interpolation)",
)


# ------------------------------------------------------------------------------------- controllers
class FormationSection(StrictModel):
    radius: float | None = Field(
        None, gt=0, description="Formation radius [m] (with `phase`; or give `offsets`)."
    )
    phase: list[float] | None = Field(
        None, description="Phase of each spacecraft on the formation circle [rad]."
    )
    offsets: list[Vec3] | None = Field(
        None,
        description=(
            "Explicit formation offsets rho_bar_iF per spacecraft [m], LVLH (instead of radius and phase)."
        ),
    )
    rotation: float = Field(0.0, description="Final rotation about the LVLH y axis [rad].")
    growth: float = Field(0.0, description="Final relative size change [-].")
    centre_offset: Vec3 = Field((0.0, 0.0, 0.0), description="Final centre offset [m].")
    chi: float | None = Field(None, gt=0, description="Time constant of the manoeuvre [s^2].")
    period: float | None = Field(
        None, gt=0, description="Reference period used to derive chi when chi is not given [s]."
    )

    @model_validator(mode="after")
    def _geometry(self):
        if (self.offsets is None) == (self.radius is None or self.phase is None):
            raise ValueError("controller.formation: give either radius and phase, or offsets")
        return self

    def component(self, n: int) -> RotatingFormation:
        if self.offsets is not None:
            if len(self.offsets) != n:
                raise ValueError(
                    f"controller.formation.offsets: {len(self.offsets)} offsets for {n} spacecraft"
                )
            offsets = np.asarray(self.offsets, dtype=float)
        else:
            phase = cast(list, self.phase)
            if len(phase) != n:
                raise ValueError(
                    f"controller.formation.phase: {len(phase)} values for {n} spacecraft"
                )
            offsets = formation_offsets(cast(float, self.radius), phase)
        if self.chi is None and self.period is None:
            raise ValueError("controller.formation: give chi [s^2] or period [s]")
        chi = (
            self.chi if self.chi is not None else chi_from_period(cast(float, self.period))
        )  # checked above
        return RotatingFormation(
            offsets=as_float(offsets),
            chi=as_float(chi),
            rotation=as_float(self.rotation),
            growth=as_float(self.growth),
            centre=as_float(self.centre_offset),
        )


class Li2020Section(StrictModel):
    formation: FormationSection
    k: float | list[float] = Field(
        0.2, description="Sliding gain k_i [1/s] (one or per spacecraft)."
    )
    lam: float | list[float] = Field(20.0, description="Feedback gain lambda_i [kg/s].")
    gamma: float | list[float] = Field(0.1, description="beta_hat adaptation gain [-].")
    eta: float | list[float] = Field(1.0, description="m_hat adaptation gain [-].")
    mu: float | list[float] = Field(1.0, description="d_hat adaptation gain [-].")
    upsilon: float | list[float] = Field(0.01, description="d_hat leakage [-].")
    m_hat0: float | list[float] = Field(100.0, description="Initial mass estimate [kg].")
    beta_hat0: float | list[float] = Field(
        1.0, description="Initial inverse-effectiveness estimate [-]."
    )
    d_hat0: float | list[float] = Field(
        0.001, description="Initial disturbance-bound estimate [N]."
    )
    sigma_a: float | list[float] = Field(
        0.001, description="a_i of the smoothing function sigma_i(t) [1/s]."
    )
    sigma_form: Literal["exponential", "inverse_square"] = Field(
        "exponential", description="Form of sigma_i(t)."
    )
    sigma_t0: float = Field(1.0, gt=0, description="t0 of the inverse-square sigma [s].")
    orbit_mu: float = Field(
        MU_EARTH, gt=0, description="Gravitational parameter of the on-board model [m^3/s^2]."
    )


def _li2020(sec: Li2020Section, ctx: BuildContext):
    require_slot(
        ctx,
        "controller",
        "reference",
        "the reference orbit of its on-board model (the natural "
        "acceleration in its regressor Y_i, eq. (8))",
    )
    n = ctx.count

    def ps(name):
        return as_float(_per_spacecraft(getattr(sec, name), n, f"controller.{name}"))

    return Li2020AdaptiveController(
        count=n,
        formation=sec.formation.component(n),
        k=ps("k"),
        lam=ps("lam"),
        gamma=ps("gamma"),
        eta=ps("eta"),
        adapt_mu=ps("mu"),
        upsilon=ps("upsilon"),
        m_hat0=ps("m_hat0"),
        beta_hat0=ps("beta_hat0"),
        d_hat0=ps("d_hat0"),
        sigma_a=ps("sigma_a"),
        sigma_t0=as_float(sec.sigma_t0),
        d_sign=as_float(1.0),
        mu=as_float(sec.orbit_mu),
        sigma_form=sec.sigma_form,
    )


class SirFtcSection(StrictModel):
    formation: FormationSection
    k: float | list[float] = Field(0.2, description="Sliding gain k_i [1/s].")
    k0: float = Field(20.0, gt=0, description="Feedback gain [kg/s].")
    phi: float = Field(1.0, gt=0, description="Boundary-layer width Phi [-].")
    sigma1: float = Field(0.01, ge=0, description="Leakage sigma_1 [1/s].")
    sigma2: float = Field(1.0, gt=0, description="Adaptation gain sigma_2 [kg/m].")
    mu_s: float = Field(0.01, gt=0, description="Smoothing mu_s [m/s].")
    b_hat0: float = Field(0.0, ge=0, description="Initial bound estimate [N].")


def _sir_ftc(sec: SirFtcSection, ctx: BuildContext):
    n = ctx.count
    return SirFtcController(
        count=n,
        formation=sec.formation.component(n),
        k=as_float(_per_spacecraft(sec.k, n, "controller.k")),
        k0=as_float(sec.k0),
        phi=as_float(sec.phi),
        sigma1=as_float(sec.sigma1),
        sigma2=as_float(sec.sigma2),
        mu_s=as_float(sec.mu_s),
        b_hat0=as_float(np.full(n, sec.b_hat0)),
    )


class PdSection(StrictModel):
    kp: float = Field(ge=0, description="Position gain [N/m].")
    kd: float = Field(ge=0, description="Velocity gain [N s/m].")
    nominal_mass: float | list[float] = Field(
        PD_NOMINAL_MASS,
        description=(
            "Mass the feed-forward uses, known on board [kg], one or per spacecraft (default 100 kg, a stated "
            "nominal value: never the plant's true masses)."
        ),
    )
    max_force: float | None = Field(None, gt=0, description="Per-axis saturation [N].")
    desired_position: Vec3Expr = Field(
        ("0", "0", "0"), description="Desired LVLH position, expressions in t, i [m]."
    )
    mode: Literal["continuous", "sampled"] = Field(
        "continuous", description="Every RK stage or held over the step."
    )


def _pd(sec: PdSection, ctx: BuildContext):
    n = ctx.count
    return PdFormationController(
        count=n,
        kp=as_float(sec.kp),
        kd=as_float(sec.kd),
        mass=as_float(_per_spacecraft(sec.nominal_mass, n, "controller.nominal_mass")),
        max_force=as_float(np.inf if sec.max_force is None else sec.max_force),
        desired_position=sec.desired_position,
        is_sampled=sec.mode == "sampled",
    )


register_component_type(
    "controller",
    "li2020-adaptive",
    Li2020Section,
    _li2020,
    "Li2020 distributed adaptive FTC (Thm 1 with a graph network, Thm 2 with a delayed one)",
)
register_component_type(
    "controller",
    "sir-ftc",
    SirFtcSection,
    _sir_ftc,
    "SIR-FTC baseline (sliding mode with an adaptive bound, no communication)",
)
register_component_type(
    "controller", "pd", PdSection, _pd, "PD formation keeping with feed-forward"
)


# -------------------------------------------------------------------------------------- actuators
class ExpressionFaultSection(StrictModel):
    effectiveness: Vec3Expr = Field(
        ("1", "1", "1"), description="Gamma(t) per axis, expressions in t, i [-]."
    )
    bias: Vec3Expr = Field(
        ("0", "0", "0"), description="Additive fault per axis, expressions in t, i [N]."
    )


def _expression_faults(sec: ExpressionFaultSection, ctx: BuildContext):
    return ExpressionFaultActuator(count=ctx.count, effectiveness=sec.effectiveness, bias=sec.bias)


class ThrusterBiasSection(StrictModel):
    """F(t) = [t >= onset] (magnitude + amplitude sin(omega t + phase) + decay_amplitude exp(-decay_rate (t - decay_origin))).
    Each field: one number, 3 values (per axis) or N x 3 values. ``per_unit_mass``: the values are
    accelerations [m/s^2] multiplied by each spacecraft's mass (the Gui2022 fault profile is written so)."""

    onset: float | list = Field(0.0, description="Onset [s].")
    magnitude: float | list = Field(0.0, description="Step part [N, or m/s^2 with per_unit_mass].")
    amplitude: float | list = Field(0.0, description="Sinusoid amplitude [N, or m/s^2].")
    omega: float | list = Field(0.0, description="Sinusoid frequency [rad/s].")
    phase: float | list = Field(0.0, description="Sinusoid phase [rad].")
    decay_amplitude: float | list = Field(0.0, description="Decaying part amplitude [N, or m/s^2].")
    decay_rate: float | list = Field(0.0, description="Decay rate [1/s].")
    decay_origin: float | list = Field(0.0, description="Origin of the decay [s].")
    per_unit_mass: bool = Field(
        False, description="Scale the force values by each spacecraft's mass."
    )


def _thruster_bias(sec: ThrusterBiasSection, ctx: BuildContext):
    n = ctx.count
    scale = np.ones((n, 1))
    if sec.per_unit_mass:
        mass = getattr(ctx.section("plant"), "mass", None)
        if mass is None:
            raise ValueError("actuator.per_unit_mass: the plant has no masses")
        scale = np.asarray(mass, float)[:, None]

    def ax(name, scaled=False):
        v = _per_axis(getattr(sec, name), n, f"actuator.{name}")
        return as_float(v * scale if scaled else v)

    return ThrusterBiasFaultActuator(
        count=n,
        onset=ax("onset"),
        magnitude=ax("magnitude", True),
        amplitude=ax("amplitude", True),
        omega=ax("omega"),
        phase=ax("phase"),
        decay_amplitude=ax("decay_amplitude", True),
        decay_rate=ax("decay_rate"),
        decay_origin=ax("decay_origin"),
        units="N",
    )


register_component_type(
    "actuator",
    "expression-faults",
    ExpressionFaultSection,
    _expression_faults,
    "loss of effectiveness and additive bias written as expressions",
)
register_component_type(
    "actuator",
    "thruster-bias",
    ThrusterBiasSection,
    _thruster_bias,
    "additive thruster fault: step + sinusoid + decaying term after an onset",
)
