"""Catalog: relative-output formation control on a chain of spacecraft pairs -- the deep-space
double-integrator plant, chain relative sensors, the relative-output law with LLFR allocation and its
FLFR weight design (Azizi & Khorasani 2009), its hierarchical (HL) supervisor (Nominal -> LLFR -> FLFR),
the step loss of actuator effectiveness and the true chain errors -- for composed scenarios on any
translational plant.

* ``plant.type = "double-integrator"``: the paper's deep-space plant ``x_i'' = b_i u_i + d_i(t)``
  (Sec. II), driven by accelerations.
* ``[[evaluations]] type = "chain-errors"``: the true chain errors ``tracking_error`` (added by the law
  itself when no scenario lists it); ``metrics = "azizi2009"`` also declares the paper's metric set.

How the parts fit a plant they were not written for:

* ``sensors.type = "chain-relative"`` measures ``x_{i+1} - x_i`` and ``v_{i+1} - v_i`` on the chain
  pairs from the plant's state: the (N, 6) relative state ``"q"`` of the relative-motion plants
  (Clohessy-Wiltshire, nonlinear LVLH) or the ``"r"``/``"v"`` states of a double-integrator plant.
* ``controller.type = "azizi2009-llfr"`` commands accelerations u_i [m/s^2]. On a force-driven
  plant it is wrapped in :class:`~formation_ftc.components.controllers._acceleration_to_force.AccelerationToForce`:
  ``f_i = m_i^nom u_i`` with the flight side's nominal masses ``controller.nominal_mass`` [kg]
  (default 100 kg, a stated nominal value: never the plant's true masses). The law models each spacecraft
  as a double integrator ``x_i'' = b_i u_i`` (deep space): any other dynamics of the plant (orbital
  relative motion, disturbances) act on it as unmodelled accelerations.
* The desired formation is the law's own: a regular N-gon of side ``controller.side`` [m] rotating at
  ``controller.omega`` [rad/s] in the plane of the plant frame's first two axes (LVLH radial /
  along-track for the relative plants), controlled through the N-1 chain outputs only (the centroid
  is not controlled).
* ``supervisor.type = "hierarchical"`` selects the law's allocation mode; it needs that law.
* ``actuator.type = "actuator-gains"``: true gains b_i and one loss of effectiveness (truth side);
  the law knows only its nominal gains and the estimate ``controller.b_hat`` of the faulty one.

A chain law without chain sensors, a supervisor without the law whose modes it selects, or a chain
sensor on a plant without positions is rejected at validation, naming both parts.
"""

from __future__ import annotations

import functools
import math
from typing import TYPE_CHECKING, Literal, TypedDict

import numpy as np
from pydantic import Field, model_validator

from formation_ftc.config.base import ExprText, StrictModel
from formation_ftc.methods.composed import (
    BuildContext,
    InitialStateRows,
    per_spacecraft,
    register_component_type,
)
from formation_ftc.sim.contract import CompositionError, as_float

if TYPE_CHECKING:
    from formation_ftc.components.evaluations.chain_errors import ChainTrackingError
    from formation_ftc.components.plants.double_integrator import DoubleIntegratorPlant
    from formation_ftc.design.flfr import FlfrDesign
    from formation_ftc.sim.metrics import Metric

DOUBLE_INTEGRATOR = "double-integrator"
CHAIN_SENSORS = "chain-relative"
#: sensors of the (N, 6) LVLH relative state from which the law and the supervisor form the chain
#: outputs on board (``y_ij = q_{i+1} - q_i``): the league's common sensor, which a residual FDI reads
STATE_SENSORS = "lvlh-relative-state"
CHAIN_LAW = "azizi2009-llfr"
HL_SUPERVISOR = "hierarchical"
CHAIN_ERRORS = "chain-errors"
AXES = ("x", "y", "z")
#: the law's nominal on-board mass when a scenario states none [kg] (``controller.nominal_mass``)
NOMINAL_MASS = 100.0
#: horizon of the simulated supremum H_i of the FLFR design (several rotation periods) [s]
DESIGN_HORIZON = 300.0
#: time of the ``effort_x_100s_sc*`` metrics of the Azizi2009 set (Fig. 2 compares the efforts there) [s]
EFFORT_TIME = 100.0
Vec3 = tuple[float, float, float]


def _plant_layout(ctx: BuildContext, slot: str, name: str) -> tuple[str, int]:
    """('q', 3) for an (N, 6) relative-state plant, ('rv', axes) for a double-integrator plant."""
    shapes = ctx.sensed_shapes() or {}  # what sensors see
    plant_name = ctx.scenario.type_of("plant")
    if shapes.get("q", ())[-1:] == (6,):
        return "q", 3
    if "r" in shapes and "v" in shapes and shapes["r"]:
        return "rv", int(shapes["r"][-1])
    keys = ", ".join(sorted(shapes)) or "none"
    raise CompositionError(
        f"{slot} {name} measures relative positions and velocities, but plant {plant_name} "
        f"({type(ctx.plant).__name__}) has no translational state (state: {keys}; needs the "
        f"(N, 6) relative state 'q' or positions 'r' and velocities 'v')"
    )


def _steps(time: float, dt: float) -> int:
    return int(round(time / dt))


# ------------------------------------------------------------------------------------------ plants
class DoubleIntegratorSection(InitialStateRows):
    """Deep space (Azizi & Khorasani 2009 Sec. II): decoupled double integrators per axis,
    ``x_i'' = a_i + d_i(t)`` with the actuator's applied acceleration ``a_i = b_i u_i`` [m/s^2]."""

    initial_position: list[Vec3] = Field(
        description="Initial inertial position per spacecraft, x, y, z [m] (the first `axes` are used)."
    )
    initial_velocity: list[Vec3] | None = Field(
        None, description="Initial inertial velocity per spacecraft, x, y, z [m/s] (default 0)."
    )
    axes: int = Field(
        3, ge=1, le=3, description="Simulated axes: 1 = x, 2 = x, y, 3 = x, y, z [-]."
    )
    disturbance_acceleration: ExprText = Field(
        "0",
        description="Disturbance d_i(t) on every axis, an expression in t [s] and i "
        "(1-based spacecraft number) [m/s^2].",
    )
    integration: Literal["exact", "rk4"] = Field(
        "exact",
        description="'exact': the exact step with the applied and disturbance accelerations held over "
        "the step (zero-order hold); 'rk4': RK4 (a 'continuous' law is re-evaluated at the stages).",
    )


def _double_integrator(sec: DoubleIntegratorSection, ctx: BuildContext) -> DoubleIntegratorPlant:
    from formation_ftc.components.plants.double_integrator import DoubleIntegratorPlant

    r0 = np.asarray(sec.initial_position, float)[:, : sec.axes]
    v0 = (
        np.zeros_like(r0)
        if sec.initial_velocity is None
        else np.asarray(sec.initial_velocity, float)[:, : sec.axes]
    )
    return DoubleIntegratorPlant(
        initial_position=as_float(r0),
        initial_velocity=as_float(v0),
        disturbance=str(sec.disturbance_acceleration),
        zoh=sec.integration == "exact",
    )


register_component_type(
    "plant",
    DOUBLE_INTEGRATOR,
    DoubleIntegratorSection,
    _double_integrator,
    "deep-space double integrators x'' = b u + d(t) per axis (Azizi2009), driven by accelerations",
)


# ----------------------------------------------------------------------------------------- sensors
class ChainRelativeSection(StrictModel):
    """Relative positions and velocities on the chain pairs (1, 2), ..., (N-1, N)."""

    position_noise_std: float = Field(
        0.0, ge=0, description="Std of the noise on x_{i+1} - x_i [m]."
    )
    velocity_noise_std: float = Field(
        0.0, ge=0, description="Std of the noise on v_{i+1} - v_i [m/s]."
    )


def _chain_relative(sec: ChainRelativeSection, ctx: BuildContext):
    from formation_ftc.components.sensors.chain_relative import ChainRelativeSensors
    from formation_ftc.components.sensors.chain_relative_state import ChainRelativeStateSensors

    layout, axes = _plant_layout(ctx, "sensors", CHAIN_SENSORS)
    if ctx.count < 2:
        raise CompositionError(
            f"sensors {CHAIN_SENSORS} need at least 2 spacecraft on the chain; plant "
            f"{ctx.scenario.type_of('plant')} has {ctx.count}"
        )
    cls = ChainRelativeStateSensors if layout == "q" else ChainRelativeSensors
    noisy = sec.position_noise_std > 0 or sec.velocity_noise_std > 0
    return cls(
        count=ctx.count,
        n_axes=axes,
        position_noise_std=as_float(sec.position_noise_std),
        velocity_noise_std=as_float(sec.velocity_noise_std),
        noisy=noisy,
    )


register_component_type(
    "sensors",
    CHAIN_SENSORS,
    ChainRelativeSection,
    _chain_relative,
    "relative position and velocity on the chain pairs (1,2), ..., (N-1,N), optional noise",
)


# ------------------------------------------------------------------------------------- controllers
class ChainLlfrSection(StrictModel):
    """Azizi & Khorasani 2009: p_ij = xdd_ij^d - lambda1 e'_ij - lambda0 e_ij on the chain pairs and the
    weighted least-effort allocation u = J_aug(alpha, b_hat)^-1 [p; 0] (eq. (3)) per axis."""

    lambda0: float = Field(gt=0, description="Position gain lambda_0 of p_ij [1/s^2].")
    lambda1: float = Field(gt=0, description="Velocity gain lambda_1 of p_ij [1/s].")
    side: float = Field(
        gt=0, description="Side of the desired regular polygon (a square for 4 spacecraft) [m]."
    )
    omega: float = Field(
        description="Rotation rate of the desired polygon about the frame's third axis [rad/s]."
    )
    alpha: float | list[float] = Field(
        1.0, description="LLFR cost weights alpha_i of eq. (3), > 0 [-]."
    )
    alpha_flfr: float | None = Field(
        None,
        gt=0,
        description="FLFR weight of the faulty spacecraft [-] (default: designed by eq. (11) from the "
        "fields below when a hierarchical supervisor may switch to FLFR -- 4 spacecraft, spacecraft "
        "2 faulty -- otherwise its LLFR weight, i.e. FLFR changes nothing).",
    )
    b: float | list[float] = Field(
        1.0, description="Nominal actuator gains b_i the law allocates with (every axis) [-]."
    )
    faulty_spacecraft: int | None = Field(
        None,
        ge=1,
        description="Spacecraft whose actuator the FDI reports faulty "
        "(1-based; none: no fault known) [-].",
    )
    faulty_axis: Literal["x", "y", "z"] = Field("x", description="Axis of the faulty actuator [-].")
    b_hat: float = Field(
        1.0, gt=0, description="FDI estimate of the faulty actuator's gain (LLFR) [-]."
    )
    nominal_mass: float | list[float] | None = Field(
        None,
        description="Masses the flight side scales the acceleration command with on a force-driven plant "
        "[kg] (default 100 kg each, a stated nominal value: never the plant's true masses; not "
        "used on an acceleration-driven plant).",
    )
    sampling: Literal["zoh", "continuous"] = Field(
        "zoh",
        description="'zoh': computed at t_k and held over the step; 'continuous': every RK stage.",
    )
    b_eps: float = Field(
        0.08,
        gt=0,
        description="Known bound B_eps on |b_hat - b| of the FDI estimate [-] (eq. (8)).",
    )
    violation_probability: float = Field(
        0.0,
        ge=0,
        lt=1,
        description="pi of eq. (11) for the FLFR weight design, 0 <= pi < 1 (0: deterministic "
        "design (9)) [-].",
    )
    disturbance_bound: float = Field(
        2e-5,
        ge=0,
        description="Bound B_ext on the differential disturbance |d_j - d_i| the FLFR design "
        "assumes [m/s^2].",
    )
    design_dt: float = Field(
        1e-3, gt=0, description="Step of the simulated H_i of the FLFR design [s]."
    )
    alpha_reference: float = Field(
        1.0, gt=0, description="alpha_k at which the FLFR design evaluates A_clp for H_i [-]."
    )

    @model_validator(mode="after")
    def _values(self):
        for name in ("alpha", "b", "nominal_mass"):
            v = getattr(self, name)
            if v is not None and any(not (x > 0 and math.isfinite(x)) for x in np.atleast_1d(v)):
                raise ValueError(f"{name} = {v}: every value must be finite and > 0")
        return self


def law_gains(
    sec: ChainLlfrSection, n: int, axes: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """The law's numbers for ``n`` spacecraft on ``axes`` axes: weights alpha (N,), nominal gains
    (N, axes), estimated gains b_hat (N, axes) (the FDI estimate on the faulty axis) and the 0-based
    faulty spacecraft k (0 when none is reported)."""
    alpha = per_spacecraft(sec.alpha, n, "controller.alpha")
    b_nom = np.tile(per_spacecraft(sec.b, n, "controller.b")[:, None], (1, axes))
    b_hat = b_nom.copy()
    k = 0
    if sec.faulty_spacecraft is not None:
        k = sec.faulty_spacecraft - 1
        if k >= n:
            raise ValueError(
                f"controller.faulty_spacecraft = {sec.faulty_spacecraft}: the plant has {n} spacecraft"
            )
        if AXES.index(sec.faulty_axis) >= axes:
            raise ValueError(
                f"controller.faulty_axis = {sec.faulty_axis!r}: the plant has {axes} axes"
            )
        b_hat[k, AXES.index(sec.faulty_axis)] = sec.b_hat
    return alpha, b_nom, b_hat, k


@functools.lru_cache(maxsize=32)
def _design_cached(key: tuple) -> FlfrDesign:
    from formation_ftc.core.polygon_formation import relative_acceleration_fn
    from formation_ftc.design.flfr import design_flfr

    alpha, b_hat, k, b_eps, lam0, lam1, e_s, pis, n, side, omega, axis, dt, b_ext, a_ref = key
    w_fn = relative_acceleration_fn(n, side, omega, axis)
    return design_flfr(
        np.asarray(alpha), np.asarray(b_hat), k, b_eps, lam0, lam1, e_s, pis, w_fn,
        DESIGN_HORIZON, dt, b_ext, a_ref,
    )  # fmt: skip


def flfr_design(
    sec: ChainLlfrSection, n: int, e_s: float, pis: tuple[float, ...] | None = None
) -> FlfrDesign:
    """Offline FLFR design of eqs. (8)-(11) (:func:`formation_ftc.design.flfr.design_flfr`) of the law
    on ``n`` spacecraft for its faulty spacecraft and axis, mission bound ``e_s`` [m] and violation
    probabilities ``pis`` (default: the law's ``violation_probability``); cached by its inputs. H_i is
    simulated over :data:`DESIGN_HORIZON` (the sup over t needs several rotation periods)."""
    if sec.faulty_spacecraft is None:
        raise ValueError("the FLFR design needs controller.faulty_spacecraft")
    axis = AXES.index(sec.faulty_axis)
    alpha, _, b_hat, k = law_gains(sec, n, axis + 1)
    pis = (sec.violation_probability,) if pis is None else pis
    key = (
        tuple(float(a) for a in alpha),
        tuple(float(b) for b in b_hat[:, axis]),
        k,
        float(sec.b_eps),
        float(sec.lambda0),
        float(sec.lambda1),
        float(e_s),
        tuple(float(p) for p in pis),
        n,
        float(sec.side),
        float(sec.omega),
        axis,
        float(sec.design_dt),
        float(sec.disturbance_bound),
        float(sec.alpha_reference),
    )
    return _design_cached(key)


def _alpha_flfr(sec: ChainLlfrSection, ctx: BuildContext, alpha: np.ndarray, k: int) -> float:
    """The FLFR weight: stated, or designed by eq. (11) for the HL supervisor's e_s (never below the
    LLFR weight), or the LLFR weight where no supervisor may switch to FLFR."""
    if sec.alpha_flfr is not None:
        return float(sec.alpha_flfr)
    sup = ctx.section("supervisor") if ctx.scenario.type_of("supervisor") == HL_SUPERVISOR else None
    if sup is None or not sup.flfr or sec.faulty_spacecraft is None:
        return float(alpha[k])
    if ctx.count != 4 or k != 1:
        raise ValueError(
            "controller.alpha_flfr: its design by eq. (11) (reduced model (7)) is implemented for 4 "
            "spacecraft with spacecraft 2 faulty; give controller.alpha_flfr"
        )
    des = flfr_design(sec, ctx.count, sup.e_s)
    if des.verdict == "infeasible":
        raise ValueError(f"controller.alpha_flfr: {des.message}")
    a = des.alpha[float(sec.violation_probability)]
    assert a is not None  # None only when infeasible (raised above)
    return max(float(a), float(alpha[k]))  # never lower the weight (LLFR already suffices)


def _chain_sensors(ctx: BuildContext, slot: str) -> bool:
    """True when the chain outputs are formed on board from ``lvlh-relative-state`` sensors, False for
    ``chain-relative`` sensors; any other sensors: a CompositionError naming ``slot`` and the sensors."""
    sensors = ctx.scenario.type_of("sensors")
    if sensors == CHAIN_SENSORS:
        return False
    if sensors == STATE_SENSORS:
        layout, _ = _plant_layout(ctx, slot, CHAIN_LAW if slot == "controller" else HL_SUPERVISOR)
        if layout == "q":
            return True
    what = (
        f"controller {CHAIN_LAW} reads relative outputs on the chain pairs"
        if slot == "controller"
        else f"supervisor {HL_SUPERVISOR} monitors the chain errors"
    )
    raise CompositionError(
        f"{what} (sensors {CHAIN_SENSORS}, or {STATE_SENSORS} on a relative-state plant: formed on "
        f"board), but sensors {sensors or 'default (exact (N, 6) state)'} measure something else"
    )


def _chain_llfr(sec: ChainLlfrSection, ctx: BuildContext):
    from formation_ftc.components.controllers._acceleration_to_force import force_from_acceleration
    from formation_ftc.components.controllers.azizi2009_llfr import ChainLlfrController
    from formation_ftc.design.allocation import validate_allocation_inputs

    n = ctx.count
    on_board = _chain_sensors(ctx, "controller")
    if sec.sampling == "continuous" and ctx.plant.integration == "exact":
        raise CompositionError(
            f"controller {CHAIN_LAW} with sampling 'continuous' is re-evaluated at the RK stages, but "
            f"plant {ctx.scenario.type_of('plant')} steps exactly with the command held: give the "
            "plant integration = 'rk4'"
        )
    layout, axes = _plant_layout(ctx, "controller", CHAIN_LAW)
    alpha, b_nom, b_hat, k = law_gains(sec, n, axes)
    for a in range(axes):
        validate_allocation_inputs(alpha, b_hat[:, a], "controller.alpha", "controller.b_hat")
    a_flfr = _alpha_flfr(sec, ctx, alpha, k)
    from formation_ftc.components.controllers.azizi2009_llfr import ChainLlfrOnBoardController

    law = (ChainLlfrOnBoardController if on_board else ChainLlfrController)(
        lambda0=as_float(sec.lambda0),
        lambda1=as_float(sec.lambda1),
        alpha=as_float(alpha),
        alpha_flfr=as_float(a_flfr),
        b_nominal=as_float(b_nom),
        b_hat=as_float(b_hat),
        side=as_float(sec.side),
        omega=as_float(sec.omega),
        fault_index=k,
        is_sampled=sec.sampling == "zoh",
        frame="LVLH" if layout == "q" else "inertial",
    )
    listed = any(e.get("type") == CHAIN_ERRORS for e in ctx.scenario.evaluations)
    if not listed and any(s.name == "position" for s in ctx.plant.signals()):
        ctx.evaluations.append(_chain_errors(ChainErrorsSection(), ctx))  # true chain errors
    quantity = ctx.plant.quantity
    if quantity == "acceleration":
        if sec.nominal_mass is not None:
            raise ValueError(
                f"controller.nominal_mass: plant {ctx.scenario.type_of('plant')} is driven by "
                "accelerations, there is no mass to scale with"
            )
        return law
    if quantity != "force":
        raise CompositionError(
            f"controller {CHAIN_LAW} commands accelerations, but plant "
            f"{ctx.scenario.type_of('plant')} is driven by a {quantity}"
        )
    mass = (
        NOMINAL_MASS if sec.nominal_mass is None else sec.nominal_mass
    )  # stated, never the plant's
    return force_from_acceleration(
        law, as_float(per_spacecraft(mass, n, "controller.nominal_mass"))
    )


register_component_type(
    "controller",
    CHAIN_LAW,
    ChainLlfrSection,
    _chain_llfr,
    "Azizi2009 relative-output chain law with LLFR allocation (deep-space double-integrator "
    "model; force plants: times the nominal masses)",
)


# ------------------------------------------------------------------------------------- supervisors
class HierarchicalSection(StrictModel):
    """HL supervisor: Nominal -> LLFR when the fault estimate arrives (at ``estimate_time``, or when the
    estimator in the loop detects the fault); LLFR -> FLFR when the measured max |e_ij| exceeds e_s
    (for ``confirm_time``, from ``monitor_start`` on)."""

    e_s: float = Field(gt=0, description="Mission error bound e_s on the chain errors [m].")
    flfr: bool = Field(True, description="Allow the switch to FLFR [-].")
    fault_information: Literal["scripted", "estimator"] = Field(
        "scripted",
        description="Source of the 'fault estimated' event (Nominal -> LLFR): 'scripted' -- at "
        "estimate_time, for the fault stated in controller.faulty_spacecraft; 'estimator' -- at the "
        "first step the [estimator]'s estimate reports 'detected' (e.g. residual-fdi), whatever the "
        "controller states [-].",
    )
    estimate_time: float = Field(
        0.0,
        ge=0,
        description="Time the fault estimate reaches the supervisor (fault_information = "
        "'scripted') [s].",
    )
    confirm_time: float = Field(
        0.0, ge=0, description="A violation must persist this long before FLFR [s]."
    )
    monitor_start: float = Field(0.0, ge=0, description="Start of the monitoring of e_s [s].")
    settle_time: float = Field(
        20.0, ge=0, description="The flag flfr_settled rises this long after the switch [s]."
    )


def _estimate_keys(ctx: BuildContext) -> set[str] | None:
    """The keys of the estimate of the loop's [estimator] as its type declares them
    (:attr:`~formation_ftc.sim.components.Estimator.estimate_keys`; None: no estimator)."""
    from formation_ftc.methods.composed import component_types

    name = ctx.scenario.type_of("estimator")
    if name is None:
        return None
    est = component_types("estimator")[("estimator", name)].build(ctx.section("estimator"), ctx)
    return set(type(est).estimate_keys)


def _check_estimator_information(ctx: BuildContext) -> None:
    """``fault_information = 'estimator'`` needs an estimator whose estimate has ``detected``."""
    name = ctx.scenario.type_of("estimator")
    keys = _estimate_keys(ctx)
    if keys is not None and "detected" in keys:
        return
    got = (
        "the loop has no [estimator]"
        if name is None
        else f"estimator {name} gives "
        + ("no estimate with named entries" if not keys else f"{{{', '.join(sorted(keys))}}}")
    )
    raise CompositionError(
        f"supervisor.fault_information = 'estimator': supervisor {HL_SUPERVISOR} switches to LLFR "
        f"when the estimator's estimate reports 'detected' (e.g. [estimator] type = "
        f'"residual-fdi"), but {got}'
    )


def _hierarchical(sec: HierarchicalSection, ctx: BuildContext):
    from formation_ftc.components.evaluations.chain_errors import ThresholdFlag
    from formation_ftc.components.supervisors.hierarchical import HierarchicalSupervisor

    law = ctx.scenario.type_of("controller")
    if law != CHAIN_LAW:
        raise CompositionError(
            f"supervisor {HL_SUPERVISOR} selects the allocation mode (Nominal / LLFR / FLFR) of "
            f"controller {CHAIN_LAW}; controller {law} has no such modes"
        )
    on_board = _chain_sensors(ctx, "supervisor")
    _, axes = _plant_layout(ctx, "supervisor", HL_SUPERVISOR)
    estimated = sec.fault_information == "estimator"
    if estimated:
        _check_estimator_information(ctx)
    c = ctx.section("controller")
    n, dt = ctx.count, ctx.dt
    never = ctx.scenario.simulation.n_steps + 1
    known = c.faulty_spacecraft is not None
    if sec.flfr and known and not 1 < c.faulty_spacecraft < n:
        raise ValueError(
            f"supervisor.flfr needs an interior faulty spacecraft (2..{n - 1}) on the chain; "
            f"controller.faulty_spacecraft = {c.faulty_spacecraft}"
        )
    ctx.evaluations.append(
        ThresholdFlag(
            name="flfr_settled",
            source="time_in_flfr",
            threshold=as_float((_steps(sec.settle_time, dt) + 0.5) * dt),
            long_name="FLFR active for longer than supervisor.settle_time",
        )
    )
    return HierarchicalSupervisor(
        count=n,
        n_axes=axes,
        side=as_float(c.side),
        omega=as_float(c.omega),
        e_s=as_float(sec.e_s),
        k_estimated=np.asarray(
            _steps(sec.estimate_time, dt) if known and not estimated else never, np.int64
        ),
        confirm_steps=np.asarray(_steps(sec.confirm_time, dt), np.int64),
        monitor_start=np.asarray(_steps(sec.monitor_start, dt), np.int64),
        flfr_enabled=np.asarray(bool(sec.flfr and known)),
        fault_information=sec.fault_information,
        on_board_chain=on_board,
    )


register_component_type(
    "supervisor",
    HL_SUPERVISOR,
    HierarchicalSection,
    _hierarchical,
    "Azizi2009 HL supervisor: Nominal -> LLFR on the fault estimate, LLFR -> FLFR when |e_ij| > e_s",
)


# -------------------------------------------------------------------------------------- actuators
class ActuatorGainsSection(StrictModel):
    """True actuator gains b_i (every axis) and one step loss of effectiveness (truth side):
    applied = b(t) * command."""

    gain: float | list[float] = Field(
        1.0, description="True actuator gains b_i before the fault [-], > 0."
    )
    spacecraft: int | None = Field(
        None, ge=1, description="Faulty spacecraft (1-based; none: no fault) [-]."
    )
    axis: Literal["x", "y", "z"] = Field("x", description="Faulty actuator axis [-].")
    effectiveness: float = Field(1.0, gt=0, le=1, description="Gain factor after the fault [-].")
    onset: float = Field(0.0, ge=0, description="Fault onset, snapped to the step grid [s].")


def _actuator_gains(sec: ActuatorGainsSection, ctx: BuildContext):
    from formation_ftc.components.actuators.actuator_gains import StepGainActuator

    n = ctx.count
    _, axes = _plant_layout(ctx, "actuator", "actuator-gains")
    gain = per_spacecraft(sec.gain, n, "actuator.gain")
    if np.any(gain <= 0):
        raise ValueError(f"actuator.gain = {gain.tolist()}: every gain must be > 0")
    b = np.tile(gain[:, None], (1, axes))
    faulty = b.copy()
    if sec.spacecraft is not None:
        if sec.spacecraft > n:
            raise ValueError(
                f"actuator.spacecraft = {sec.spacecraft}: plant {ctx.scenario.type_of('plant')} "
                f"has {n} spacecraft"
            )
        if AXES.index(sec.axis) >= axes:
            raise ValueError(f"actuator.axis = {sec.axis!r}: the plant has {axes} axes")
        faulty[sec.spacecraft - 1, AXES.index(sec.axis)] *= sec.effectiveness
    return StepGainActuator(
        gain=as_float(b),
        faulty_gain=as_float(faulty),
        onset=as_float(_steps(sec.onset, ctx.dt) * ctx.dt),
    )


register_component_type(
    "actuator",
    "actuator-gains",
    ActuatorGainsSection,
    _actuator_gains,
    "true actuator gains with a step loss of effectiveness on one axis (applied = b(t) u)",
)


# ------------------------------------------------------------------------------------ evaluations
class ChainErrorsSection(StrictModel):
    """True chain errors ``tracking_error`` e_ij = (x_j - x_i) - (x_j^d - x_i^d) on the pairs (1, 2),
    ..., (N-1, N), from the plant's positions and the law's desired polygon (records and metrics)."""

    metrics: Literal["none", "azizi2009"] = Field(
        "none",
        description="'azizi2009': also compute the paper's metric set -- max_err (largest |e_ij|), "
        "max_err_x, effort_x_sc* (int u_x^2 dt) and effort_x_100s_sc* (at 100 s, when the horizon "
        "reaches it) where the plant records its effort, and max_err_after_flfr, t_flfr, n_events "
        "with the hierarchical supervisor.",
    )


class _MetricOptions(TypedDict, total=False):
    """Keyword arguments of :class:`Metric` shared by several metrics of one set."""

    norm: bool
    norm_ord: str
    spacecraft: str
    units: str
    component: int


def _azizi2009_metrics(ctx: BuildContext) -> list[Metric]:
    """Azizi2009's metric set (see :class:`ChainErrorsSection`)."""
    from formation_ftc.blocks.supervisors.hierarchical_supervisor import FLFR
    from formation_ftc.sim.metrics import Metric

    worst: _MetricOptions = {"norm": True, "norm_ord": "inf", "spacecraft": "max", "units": "m"}
    out = [
        Metric("max_err", "tracking_error", reduce="max", **worst),
        Metric(
            "max_err_x",
            "tracking_error",
            reduce="max",
            norm=True,
            component=0,
            spacecraft="max",
            units="m",
        ),
    ]
    if ctx.scenario.type_of("supervisor") == HL_SUPERVISOR:
        out += [
            Metric(
                "max_err_after_flfr", "tracking_error", reduce="max", gate="flfr_settled", **worst
            ),
            Metric("t_flfr", "mode", reduce="first", threshold=as_float(FLFR), units="s"),
            Metric("n_events", "mode_changes", reduce="final"),
        ]
    if any(s.name == "effort" for s in ctx.plant.signals()):
        effort: _MetricOptions = {"component": 0, "spacecraft": "each", "units": "m2 s-3"}
        out.append(Metric("effort_x", "effort", reduce="final", **effort))
        if ctx.horizon >= EFFORT_TIME - 1e-9:
            out.append(
                Metric(
                    "effort_x_100s", "effort", reduce="at", start=as_float(EFFORT_TIME), **effort
                )
            )
    return out


def _chain_errors(sec: ChainErrorsSection, ctx: BuildContext) -> ChainTrackingError:
    from formation_ftc.components.evaluations.chain_errors import ChainTrackingError

    if sec.metrics == "azizi2009":
        ctx.metrics.extend(_azizi2009_metrics(ctx))
    return ChainTrackingError()


register_component_type(
    "evaluation",
    CHAIN_ERRORS,
    ChainErrorsSection,
    _chain_errors,
    "true chain errors e_ij (tracking_error); metrics = 'azizi2009': the paper's metric set",
)
