"""Catalog: translational plants, reference orbits, relative-state sensors, graph networks, formation
laws and thruster faults for composed scenarios."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, ClassVar, Literal, cast

import numpy as np
from pydantic import Field, field_validator, model_validator

from formation_ftc.config.base import ExprText, StrictModel
from formation_ftc.core.constants import MU_EARTH
from formation_ftc.core.graph import GraphError, validate_adjacency
from formation_ftc.core.rounding import eigenvalue_margin
from formation_ftc.methods.composed import (
    BuildContext,
    ComposedScenario,
    per_spacecraft,
    register_component_type,
    register_conditions,
    require_slot,
)
from formation_ftc.registry import Condition
from formation_ftc.sim.contract import as_float

if TYPE_CHECKING:
    from formation_ftc.components.controllers.desired_formation import RotatingFormation
    from formation_ftc.sim.loop import ClosedLoop

Vec3 = tuple[float, float, float]
Vec3Expr = tuple[ExprText, ExprText, ExprText]


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

    @model_validator(mode="after")
    def _finite_mean_motion(self):
        try:
            n = self.mean_motion
        except ArithmeticError:  # a^3 overflows or underflows float64
            n = math.nan
        if not (n > 0 and math.isfinite(n)):
            raise ValueError(
                f"semi_major_axis = {self.semi_major_axis:g} m: the mean motion sqrt(mu / a^3) "
                "[rad/s] is not a finite float64 > 0"
            )
        return self

    @property
    def mean_motion(self) -> float:
        return math.sqrt(self.mu / self.semi_major_axis**3)


def _cw_plant(sec: CwPlantSection, ctx: BuildContext):
    from formation_ftc.components.plants.clohessy_wiltshire import ClohessyWiltshirePlant

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
    from formation_ftc.components.plants.relative_lvlh import RelativeLvlhPlant

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
    from formation_ftc.components.references.keplerian import KeplerianReference

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
    from formation_ftc.components.sensors.exact_relative_state import ExactRelativeStateSensors
    from formation_ftc.components.sensors.relative_state import RelativeStateSensors

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
        if len({len(r) for r in self.adjacency} | {len(self.adjacency)}) != 1:
            raise ValueError("adjacency: must be square (N x N)")
        try:  # finite, >= 0, no self-loops
            validate_adjacency(self.adjacency, field="adjacency")
        except GraphError as exc:
            raise ValueError(str(exc)) from None
        return self


class DelayedGraphSection(GraphSection):
    delays: list[list[ExprText]] = Field(
        description="T_ij(t) per link, expressions in t, i (receiver), j (sender) [s] (N x N, row i = "
        "receiver; the diagonal and unused links are not read); >= 0 on the used links."
    )
    max_delay: float = Field(
        gt=0, description="Largest delay on any used link [s] (sizes the history buffer)."
    )


def _graph(sec: GraphSection, ctx: BuildContext):
    from formation_ftc.components.networks.weighted_graph import GraphNetwork

    return GraphNetwork(weights=as_float(validate_adjacency(sec.adjacency, ctx.count)))


def _delayed_graph(sec: DelayedGraphSection, ctx: BuildContext):
    """The delays of the used links, sampled at every step of the horizon, must stay in [0, max_delay]
    (the history holds max_delay seconds); when they also stay >= dt the reads never need the message
    sent within the step, and that blend is left out (``short_delays``)."""
    from formation_ftc.components.networks.weighted_graph import (
        DelayedGraphNetwork,
        delay_statistics,
        graph_edges,
    )
    from formation_ftc.core.history import required_capacity

    n = len(validate_adjacency(sec.adjacency, ctx.count))
    if len(sec.delays) != n or any(len(r) != n for r in sec.delays):
        raise ValueError(f"network.delays: must be {n} x {n} like network.adjacency")
    edges = graph_edges(sec.adjacency)
    texts = tuple(tuple(str(x) for x in r) for r in sec.delays)
    stats = {st.pair: st for st in delay_statistics(texts, ctx.horizon, ctx.dt)}
    for i, j in edges:
        st = stats[(i, j)]
        where = f"network.delays[{i}][{j}] ({st.name}, link {j + 1} -> {i + 1})"
        if st.value_min < 0:
            raise ValueError(
                f"{where}: delay goes negative at t = {st.t_first_negative:.6g} s (minimum "
                f"T = {st.value_min:.6g} s at t = {st.t_min:.6g} s; delays must be >= 0 s)"
            )
        if st.value_max > sec.max_delay:
            raise ValueError(
                f"{where}: T = {st.value_max:.6g} s at t = {st.t_max:.6g} s exceeds "
                f"network.max_delay = {sec.max_delay:g} s (the history holds max_delay seconds)"
            )
    return DelayedGraphNetwork(
        weights=as_float(sec.adjacency),
        delays=texts,
        edges=edges,
        capacity=required_capacity(sec.max_delay, ctx.dt) + 1,
        dt=ctx.dt,
        short_delays=any(stats[e].value_min < ctx.dt for e in edges),
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
        from formation_ftc.components.controllers.desired_formation import RotatingFormation
        from formation_ftc.core.rotating_formation import chi_from_period, formation_offsets

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
    """Li2020 adaptive FTC: Thm 1 (eqs. (23)-(27)) over a ``graph`` network, Thm 2 (eqs. (41)-(45))
    over a ``delayed-graph``. Per-spacecraft fields take one number or N."""

    #: fields whose Li2020AdaptiveController attribute has another name (campaign.binding)
    leaf_paths: ClassVar[dict[str, str]] = {"mu": "adapt_mu", "orbit_mu": "mu"}
    formation: FormationSection
    k: float | list[float] = Field(
        0.2, description="k_i of s_i = e_i2 + k_i e_i1 (eq. (6)) [1/s], > 0 (Lemma 2)."
    )
    lam: float | list[float] = Field(
        20.0, description="lambda_i [kg/s] (Li2020: Thm 1 20, Thm 2 15)."
    )
    gamma: float | list[float] = Field(
        0.1,
        description="gamma_i, beta_hat adaptation gain [s/(kg m^2)] (not in the paper: our choice, "
        "E000-12).",
    )
    eta: float | list[float] = Field(
        1.0,
        description="eta_i, m_hat adaptation gain [kg s/m^2] (not in the paper: our choice, E000-12).",
    )
    mu: float | list[float] = Field(
        1.0,
        description="mu_i, d_hat adaptation gain [N s/m] (not in the paper: our choice, E000-12).",
    )
    upsilon: float | list[float] = Field(
        0.01,
        description="upsilon_i, d_hat leakage gain [1/(N s)] per unit sigma (not in the paper: our "
        "choice, E000-12).",
    )
    m_hat0: float | list[float] = Field(
        100.0, description="m_hat_i(0), initial mass estimate [kg], > 0 (nominal, stated)."
    )
    beta_hat0: float | list[float] = Field(
        1.0, description="beta_hat_i(0), initial inverse-effectiveness estimate [-]."
    )
    d_hat0: float | list[float] = Field(
        0.001, description="d_hat_i(0), initial disturbance-bound estimate [N], > 0 (eq. (27))."
    )
    sigma_a: float | list[float] = Field(
        0.001,
        description="a_i of sigma_i(t) [1/s] (exponential) or [1/s^2] (inverse square), > 0.",
    )
    sigma_form: Literal["exponential", "inverse_square"] = Field(
        "exponential",
        description="sigma_i(t): 'exponential' exp(-a t) (eq. (13)) or 'inverse_square' "
        "1/(a (t + t0)^2) (eq. (14), shifted by t0).",
    )
    sigma_t0: float = Field(1.0, gt=0, description="t0 of the inverse-square sigma [s].")
    orbit_mu: float = Field(
        MU_EARTH, gt=0, description="Gravitational parameter of the on-board model [m^3/s^2]."
    )
    dhat_sign_literal: bool = Field(
        False,
        description="Use the printed sign of the d_hat tanh term (+ in eq. (24), Thm 1; - in eq. (42), "
        "Thm 2, i.e. over a delayed network) instead of + in both (E000-04).",
    )

    @field_validator("k", "m_hat0", "d_hat0", "sigma_a")
    @classmethod
    def _positive(cls, v, info):
        vals = v if isinstance(v, list) else [v]
        if any(not x > 0 for x in vals):
            raise ValueError(f"{info.field_name} must be > 0, got {v}")
        return v


def _li2020(sec: Li2020Section, ctx: BuildContext):
    from formation_ftc.components.controllers.li2020_adaptive import Li2020AdaptiveController

    require_slot(
        ctx,
        "controller",
        "reference",
        "the reference orbit of its on-board model (the natural "
        "acceleration in its regressor Y_i, eq. (8))",
    )
    n = ctx.count

    def ps(name):
        return as_float(per_spacecraft(getattr(sec, name), n, f"controller.{name}"))

    # the printed '-' of eq. (42) belongs to Thm 2, the law over delayed links (E000-04)
    delayed = getattr(ctx.section("network"), "delays", None) is not None
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
        d_sign=as_float(-1.0 if sec.dhat_sign_literal and delayed else 1.0),
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
    from formation_ftc.components.controllers.sir_ftc import SirFtcController

    n = ctx.count
    return SirFtcController(
        count=n,
        formation=sec.formation.component(n),
        k=as_float(per_spacecraft(sec.k, n, "controller.k")),
        k0=as_float(sec.k0),
        phi=as_float(sec.phi),
        sigma1=as_float(sec.sigma1),
        sigma2=as_float(sec.sigma2),
        mu_s=as_float(sec.mu_s),
        b_hat0=as_float(np.full(n, sec.b_hat0)),
    )


class PdSection(StrictModel):
    #: fields whose PdFormationController attribute has another name (campaign.binding)
    leaf_paths: ClassVar[dict[str, str]] = {"nominal_mass": "mass"}
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
        ("0", "0", "0"),
        description="Desired LVLH position p^d(t) per axis [m], expressions in t [s] and i.",
    )
    mode: Literal["continuous", "sampled"] = Field(
        "continuous", description="Every RK stage or held over the step."
    )


def _pd(sec: PdSection, ctx: BuildContext):
    from formation_ftc.components.controllers.pd_formation import PdFormationController

    n = ctx.count
    return PdFormationController(
        count=n,
        kp=as_float(sec.kp),
        kd=as_float(sec.kd),
        mass=as_float(per_spacecraft(sec.nominal_mass, n, "controller.nominal_mass")),
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


class NoControlSection(StrictModel):
    """No fields: the command is zero."""


def _no_control(sec: NoControlSection, ctx: BuildContext):
    from formation_ftc.components.controllers._output_feedback import FreeDrift
    from formation_ftc.components.controllers.pd_formation import ZeroController

    if ctx.plant.quantity == "acceleration":  # u = 0 [m/s^2] (e.g. Gui2022's observer runs)
        return FreeDrift(count=ctx.count)
    return ZeroController(count=ctx.count)


register_component_type(
    "controller", "none", NoControlSection, _no_control, "no control (free drift): u = 0"
)


def rk4_amplification(z: np.ndarray) -> np.ndarray:
    """|R(z)| of classical RK4, the amplification of one step of a linear mode.

    Parameters
    ----------
    z : array_like
        Eigenvalue times step, lambda dt [-] (complex).

    Returns
    -------
    numpy.ndarray
        |R(z)| = |1 + z + z^2/2 + z^3/6 + z^4/24| [-]: the mode is integrated stably when <= 1.
    """
    z = np.asarray(z, dtype=complex)
    return np.abs(1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24)


def cw_linear_conditions(s: ComposedScenario, loop: ClosedLoop) -> list[Condition]:
    """PD (or no control) on the CW plant: the closed-loop eigenvalues of A - B [kp kd]/m_i (true
    masses m_i [kg]) must have negative real parts, and the RK4 step must integrate every closed-loop
    mode stably (|R(lambda dt)| <= 1). Both are exact for the linear model up to the eigenvalues'
    rounding margin (:func:`formation_ftc.core.rounding.eigenvalue_margin`): a real part within the
    margin of 0 does not count as stable. Other plants are outside the linear model: no condition.

    Parameters
    ----------
    s : ComposedScenario
        A scenario whose controller is ``pd`` or ``none``.
    loop : ClosedLoop
        Its built loop (unused: the numbers are read from the sections).

    Returns
    -------
    list of Condition
        One stability condition per spacecraft (``pd`` only) and the RK4 step condition.
    """
    from formation_ftc.core.dynamics.cw import cw_matrices

    if s.type_of("plant") != "clohessy-wiltshire":
        return []
    plant = s.section("plant")
    A, B = cw_matrices(plant.mean_motion)
    out = []
    if s.type_of("controller") != "pd":
        eigs = [np.linalg.eigvals(A)]
        margins = [np.full(A.shape[0], eigenvalue_margin(A))]
    else:
        pd = s.section("controller")
        eigs, margins = [], []
        for i, m in enumerate(plant.mass):
            with np.errstate(over="raise"):  # a subnormal mass: FloatingPointError, not inf gains
                K = np.hstack([pd.kp * np.eye(3), pd.kd * np.eye(3)]) / m
            M = A - B @ K  # closed loop of the linear CW model
            ev = np.linalg.eigvals(M)
            tol = eigenvalue_margin(M)
            eigs.append(ev)
            margins.append(np.full(ev.shape, tol))
            out.append(
                Condition(
                    name=f"closed-loop stable, spacecraft {i + 1}",
                    reference="linear CW + PD",
                    value=f"max Re(eig) = {ev.real.max():.4g} 1/s",
                    requirement=f"< -{tol:.2g} (rounding margin)",
                    holds=bool(ev.real.max() < -tol),
                    required=True,
                    basis="exact",
                    detail="exact: eigenvalues of the 6 x 6 closed-loop matrix (LAPACK, float64), "
                    f"rounding margin {tol:.2g} 1/s (Bauer-Fike: kappa(V) 10 n eps ||A - BK||)",
                )
            )
    ev_all = np.concatenate(eigs)
    tol_all = np.concatenate(margins)
    dt = s.simulation.dt
    amp = rk4_amplification(ev_all * dt)
    worst = int(np.argmax(amp))
    stable_modes = ev_all.real < -tol_all
    # a mode that is stable in continuous time must stay damped by the RK4 step (|R| <= 1)
    ok = bool(np.all(amp[stable_modes] <= 1.0)) if stable_modes.any() else True
    out.append(
        Condition(
            name="RK4 step vs closed-loop modes",
            reference="RK4 stability region",
            value=f"dt max|lambda| = {dt * np.abs(ev_all).max():.3g}, max |R(lambda dt)| = "
            f"{amp.max():.4g} (at lambda = {ev_all[worst]:.3g} 1/s)",
            requirement="|R(lambda dt)| <= 1 for every stable mode",
            holds=ok,
            required=True,
            basis="exact",
            detail="exact for the linear closed loop: RK4 amplification factor R(z) = 1 + z + z^2/2 "
            "+ z^3/6 + z^4/24 evaluated at every closed-loop eigenvalue times dt (LAPACK "
            "eigenvalues; modes within the rounding margin of the imaginary axis are not counted "
            "as stable)",
        )
    )
    return out


register_conditions("controller", "pd", cw_linear_conditions)
register_conditions("controller", "none", cw_linear_conditions)


# -------------------------------------------------------------------------------------- actuators
class ExpressionFaultSection(StrictModel):
    effectiveness: Vec3Expr = Field(
        ("1", "1", "1"), description="Gamma(t) per axis, expressions in t, i [-]."
    )
    bias: Vec3Expr = Field(
        ("0", "0", "0"), description="Additive fault per axis, expressions in t, i [N]."
    )


def _expression_faults(sec: ExpressionFaultSection, ctx: BuildContext):
    from formation_ftc.components.actuators.expression_faults import ExpressionFaultActuator

    return ExpressionFaultActuator(count=ctx.count, effectiveness=sec.effectiveness, bias=sec.bias)


class StepFaultSection(StrictModel):
    """alpha_ij(t) = effectiveness[i][j] from onset[i][j] on, 1 before (Li2020 eq. (5)); numbers, not
    expressions, so that campaigns vary them without recompiling."""

    #: fields whose StepFaultActuator attribute has another name (campaign.binding)
    leaf_paths: ClassVar[dict[str, str]] = {"effectiveness": "alpha"}
    effectiveness: list[Vec3] = Field(
        description="Effectiveness after the onset per spacecraft and axis, in (0, 1] [-] (N x 3)."
    )
    onset: list[Vec3] = Field(
        description="Onset per spacecraft and axis, >= 0 [s] (N x 3; snapped to the step grid)."
    )
    bias: Vec3Expr = Field(
        ("0", "0", "0"), description="Additive fault per axis, expressions in t, i [N]."
    )

    @model_validator(mode="after")
    def _ranges(self):
        for name, ok, rng, unit in (
            ("effectiveness", lambda v: 0.0 < v <= 1.0, "(0, 1]", "-"),
            ("onset", lambda v: v >= 0.0, ">= 0", "s"),
        ):
            for i, row in enumerate(getattr(self, name)):
                for j, v in enumerate(row):
                    if not ok(v):
                        raise ValueError(f"{name}[{i}][{j}] = {v}: must be {rng} [{unit}]")
        return self


def _step_faults(sec: StepFaultSection, ctx: BuildContext):
    from formation_ftc.components.actuators.step_faults import StepFaultActuator

    for name in ("effectiveness", "onset"):
        rows = len(getattr(sec, name))
        if rows != ctx.count:
            raise ValueError(f"actuator.{name}: {rows} rows for {ctx.count} spacecraft (N x 3)")
    # onsets snapped to the step grid so that no RK step straddles a fault onset
    onset = np.round(np.asarray(sec.onset, float) / ctx.dt) * ctx.dt
    return StepFaultActuator(
        alpha=as_float(sec.effectiveness),
        onset=as_float(onset),
        bias=cast(Vec3Expr, tuple(sec.bias)),
    )


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
    from formation_ftc.components.actuators.thruster_bias import ThrusterBiasFaultActuator

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
        units="m s-2" if ctx.plant.quantity == "acceleration" else "N",
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
    "step-faults",
    StepFaultSection,
    _step_faults,
    "step loss of effectiveness per spacecraft and axis (numbers) and additive bias expressions",
)
register_component_type(
    "actuator",
    "thruster-bias",
    ThrusterBiasSection,
    _thruster_bias,
    "additive thruster fault: step + sinusoid + decaying term after an onset",
)
