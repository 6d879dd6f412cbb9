"""Catalog: relative-output formation control on a chain of spacecraft pairs -- chain relative
sensors, the relative-output law with LLFR allocation (Azizi & Khorasani 2009), its hierarchical (HL)
supervisor (Nominal -> LLFR -> FLFR) and the step loss of actuator effectiveness -- for composed
scenarios on any translational plant.

How the parts fit a plant they were not written for:

* ``sensors.type = "chain-relative"`` measures ``x_{i+1} - x_i`` and ``v_{i+1} - v_i`` on the chain
  pairs from the plant's state: the (N, 6) relative state ``"q"`` of the relative-motion plants
  (Clohessy-Wiltshire, nonlinear LVLH) or the ``"r"``/``"v"`` states of a double-integrator plant.
* ``controller.type = "azizi2009-llfr"`` commands accelerations u_i [m/s^2]. On a force-driven
  plant it is wrapped in :class:`~formation_ftc.components.controllers.acceleration_to_force.AccelerationToForce`:
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

import math
from typing import Literal

import numpy as np
from pydantic import Field, model_validator

from formation_ftc.components.actuators.actuator_gains import StepGainActuator
from formation_ftc.components.controllers.acceleration_to_force import force_from_acceleration
from formation_ftc.components.controllers.azizi2009_llfr import ChainLlfrController
from formation_ftc.components.evaluations.chain_errors import ChainTrackingError, ThresholdFlag
from formation_ftc.components.sensors.chain_relative import ChainRelativeSensors
from formation_ftc.components.sensors.chain_relative_state import ChainRelativeStateSensors
from formation_ftc.components.supervisors.hierarchical import HierarchicalSupervisor
from formation_ftc.config.base import StrictModel
from formation_ftc.design.allocation import validate_allocation_inputs
from formation_ftc.methods.composed import BuildContext, per_spacecraft, register_component_type
from formation_ftc.sim.components import CompositionError, as_float

CHAIN_SENSORS = "chain-relative"
CHAIN_LAW = "azizi2009-llfr"
HL_SUPERVISOR = "hierarchical"
AXES = ("x", "y", "z")
#: the law's nominal on-board mass when a scenario states none [kg] (``controller.nominal_mass``)
NOMINAL_MASS = 100.0


_per_spacecraft = per_spacecraft


def _plant_layout(ctx: BuildContext, slot: str, name: str) -> tuple[str, int]:
    """('q', 3) for an (N, 6) relative-state plant, ('rv', axes) for a double-integrator plant."""
    plant = ctx.plant
    state = (
        plant.sensed_state(plant.initial_state()) if plant is not None else None
    )  # what sensors see
    plant_name = ctx.scenario.type_of("plant")
    if isinstance(state, dict) and "q" in state and np.shape(state["q"])[-1] == 6:
        return "q", 3
    if isinstance(state, dict) and "r" in state and "v" in state:
        return "rv", int(np.shape(state["r"])[-1])
    keys = ", ".join(sorted(state)) if isinstance(state, dict) else type(state).__name__
    raise CompositionError(
        f"{slot} {name} measures relative positions and velocities, but plant {plant_name} "
        f"({type(plant).__name__}) has no translational state (state: {keys}; needs the "
        f"(N, 6) relative state 'q' or positions 'r' and velocities 'v')"
    )


def _steps(time: float, dt: float) -> int:
    return int(round(time / dt))


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
        description="FLFR weight of the faulty spacecraft [-] "
        "(default: its LLFR weight, i.e. FLFR changes nothing).",
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

    @model_validator(mode="after")
    def _values(self):
        for name in ("alpha", "b", "nominal_mass"):
            v = getattr(self, name)
            if v is not None and any(not (x > 0 and math.isfinite(x)) for x in np.atleast_1d(v)):
                raise ValueError(f"{name} = {v}: every value must be finite and > 0")
        return self


def _chain_llfr(sec: ChainLlfrSection, ctx: BuildContext):
    n = ctx.count
    sensors = ctx.scenario.type_of("sensors")
    if sensors != CHAIN_SENSORS:
        raise CompositionError(
            f"controller {CHAIN_LAW} reads relative outputs on the chain pairs (sensors {CHAIN_SENSORS}), but "
            f"sensors {sensors or 'default (exact (N, 6) state)'} measure something else"
        )
    layout, axes = _plant_layout(ctx, "controller", CHAIN_LAW)
    alpha = _per_spacecraft(sec.alpha, n, "controller.alpha")
    b_nom = np.tile(_per_spacecraft(sec.b, n, "controller.b")[:, None], (1, axes))
    b_hat = b_nom.copy()
    k = 0
    if sec.faulty_spacecraft is not None:
        k = sec.faulty_spacecraft - 1
        if k >= n:
            raise ValueError(
                f"controller.faulty_spacecraft = {sec.faulty_spacecraft}: plant "
                f"{ctx.scenario.type_of('plant')} has {n} spacecraft"
            )
        if AXES.index(sec.faulty_axis) >= axes:
            raise ValueError(
                f"controller.faulty_axis = {sec.faulty_axis!r}: the plant has {axes} axes"
            )
        b_hat[k, AXES.index(sec.faulty_axis)] = sec.b_hat
    for a in range(axes):
        validate_allocation_inputs(alpha, b_hat[:, a], "controller.alpha", "controller.b_hat")
    a_flfr = alpha[k] if sec.alpha_flfr is None else sec.alpha_flfr
    law = ChainLlfrController(
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
    if any(s.name == "position" for s in ctx.plant.signals()):
        ctx.evaluations.append(ChainTrackingError())  # true chain errors (records and metrics only)
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
        law, as_float(_per_spacecraft(mass, n, "controller.nominal_mass"))
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
    """HL supervisor: Nominal -> LLFR when the fault estimate arrives; LLFR -> FLFR when the measured
    max |e_ij| exceeds e_s (for ``confirm_time``, from ``monitor_start`` on)."""

    e_s: float = Field(gt=0, description="Mission error bound e_s on the chain errors [m].")
    flfr: bool = Field(True, description="Allow the switch to FLFR [-].")
    estimate_time: float = Field(
        0.0, ge=0, description="Time the fault estimate reaches the supervisor [s]."
    )
    confirm_time: float = Field(
        0.0, ge=0, description="A violation must persist this long before FLFR [s]."
    )
    monitor_start: float = Field(0.0, ge=0, description="Start of the monitoring of e_s [s].")
    settle_time: float = Field(
        20.0, ge=0, description="The flag flfr_settled rises this long after the switch [s]."
    )


def _hierarchical(sec: HierarchicalSection, ctx: BuildContext):
    law = ctx.scenario.type_of("controller")
    if law != CHAIN_LAW:
        raise CompositionError(
            f"supervisor {HL_SUPERVISOR} selects the allocation mode (Nominal / LLFR / FLFR) of "
            f"controller {CHAIN_LAW}; controller {law} has no such modes"
        )
    sensors = ctx.scenario.type_of("sensors")
    if sensors != CHAIN_SENSORS:
        raise CompositionError(
            f"supervisor {HL_SUPERVISOR} monitors the chain errors of sensors {CHAIN_SENSORS}, "
            f"but sensors {sensors or 'default (exact (N, 6) state)'} measure something else"
        )
    _, axes = _plant_layout(ctx, "supervisor", HL_SUPERVISOR)
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
        dt=float(dt),
        side=as_float(c.side),
        omega=as_float(c.omega),
        e_s=as_float(sec.e_s),
        k_estimated=np.asarray(_steps(sec.estimate_time, dt) if known else never, np.int64),
        confirm_steps=np.asarray(_steps(sec.confirm_time, dt), np.int64),
        monitor_start=np.asarray(_steps(sec.monitor_start, dt), np.int64),
        flfr_enabled=np.asarray(bool(sec.flfr and known)),
        t0=0.0,
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
    n = ctx.count
    _, axes = _plant_layout(ctx, "actuator", "actuator-gains")
    gain = _per_spacecraft(sec.gain, n, "actuator.gain")
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
