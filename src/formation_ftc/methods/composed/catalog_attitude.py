"""Catalog: quaternion rigid-body attitudes, Euler-angle attitude sensors, the networked Euler-Lagrange
H-infinity / adaptive attitude law, its generalised-torque allocation with additive faults and the
scripted FDI, for composed scenarios.

The attitude law (``controller.type = "networked-el-hinf"``) is written in 3-2-1 Euler angles and
commands a generalised torque; the quaternion plant (``plant.type = "quaternion-rigid-body"``) has a
quaternion state and is driven by a body torque. The two fit through

* ``sensors.type = "quaternion-euler"`` -- quaternion -> ``[theta, phi, psi]`` (Z-Y-X), body rates
  passed through (the law forms ``q_dot = R_bar(q) omega``);
* ``actuator.type = "euler-torque-allocation"`` -- ``tau_body = R_bar(q)^T (tau_gen + u_bar)`` with the
  additive faults ``u_bar`` in the law's channels (equal power ``tau_body . omega = tau_gen . q_dot``).

A composition of the law on the quaternion plant without either is rejected at validation, naming
both parts (see :mod:`formation_ftc.core.euler_quaternion` for the conversions).

The Euler-angle plant (``plant.type = "euler-angle-attitude"``, Mehrabian (1), (27)-(28)) has the law's
own state and input: the law reads its state directly (no ``[sensors]``), and
``euler-torque-allocation`` applies its additive faults to the generalised torque without a mapping.
``[[evaluations]] type = "mehrabian-metrics"`` declares Mehrabian's metric set (synchronisation and
tracking errors, effort, spreads over the fault window, the run and the assessment window).
"""

from __future__ import annotations

import functools
import math
from typing import TYPE_CHECKING, Any, ClassVar, Literal, TypedDict

import numpy as np
from pydantic import Field, model_validator

from formation_ftc.config.base import ExprText, StrictModel
from formation_ftc.core import graph as graphs
from formation_ftc.core.constants import SINGULAR_PITCH_LIMIT_RAD, check_away_from_singularity
from formation_ftc.methods.composed import BuildContext, register_component_type
from formation_ftc.sim.contract import CompositionError, as_float

if TYPE_CHECKING:
    from formation_ftc.components.plants.quaternion_rigid_body import QuaternionRigidBodyPlant

Vec3 = tuple[float, float, float]
Vec3Expr = tuple[ExprText, ExprText, ExprText]


# Build-time conversions of a section's initial attitude, each one compiled program: evaluated operation
# by operation they compiled about 50 small programs (1.4-1.5 s) the first time a process loaded such a
# scenario.
@functools.cache
def _quaternion_from_euler():
    """The jitted ZYX Euler -> quaternion map (compiled on first use: JAX is imported by builds only)."""
    import jax

    from formation_ftc.core.euler_quaternion import quaternion_from_euler_zyx

    return jax.jit(quaternion_from_euler_zyx)


@functools.cache
def _euler_from_quaternion():
    """The jitted quaternion -> ZYX Euler map (compiled on first use)."""
    import jax

    from formation_ftc.core.euler_quaternion import euler_zyx_from_quaternion

    return jax.jit(euler_zyx_from_quaternion)


QUATERNION_PLANT = "quaternion-rigid-body"
EULER_PLANT = "euler-angle-attitude"
MEHRABIAN_METRICS = "mehrabian-metrics"
EULER_SENSORS = "quaternion-euler"
EULER_LAW = "networked-el-hinf"
EULER_ALLOCATION = "euler-torque-allocation"
SCRIPTED_FDI = "scripted-fdi"
#: the Euler-angle law's model inertia when a scenario states none [kg m^2] (``controller.nominal_inertia``):
#: Mehrabian's nominal J^ (our choice E003-10); also the default principal inertia about which the
#: Euler-angle plant draws its true inertias
NOMINAL_INERTIA = (20.0, 18.0, 15.0)
#: plant types whose state is {"omega": (N, 3), "q": (N, 4)} (body rate, quaternion vector first): the Euler
#: sensors, the torque allocation and the Euler-angle law accept them; other catalogs add theirs
QUATERNION_PLANTS: set[str] = {QUATERNION_PLANT}


def _vec3_text(v: Vec3Expr) -> tuple[str, str, str]:
    a, b, c = v
    return str(a), str(b), str(c)


# ----------------------------------------------------------------------------------------- plants
class RigidBodyAttitudeSection(StrictModel):
    """Fields shared by the rigid-body attitude plants: principal inertia, initial attitude (Euler
    angles or quaternions), initial body rate and disturbance torque, with their checks."""

    inertia: Vec3 = Field(
        description="Principal inertia diag(J) of every spacecraft [kg m^2], each > 0."
    )
    initial_attitude_deg: list[Vec3] | None = Field(
        None,
        description="Initial 3-2-1 Euler angles [theta (pitch), phi (roll), psi (yaw)] per spacecraft "
        "[deg] (converted to quaternions; give this or initial_quaternion).",
    )
    initial_quaternion: list[tuple[float, float, float, float]] | None = Field(
        None,
        description="Initial unit quaternion [q1, q2, q3, q4] (vector first) per spacecraft [-].",
    )
    initial_body_rate: list[Vec3] | None = Field(
        None,
        description="Initial body angular velocity per spacecraft, body axes [rad/s] (default 0).",
    )
    disturbance_torque: Vec3Expr = Field(
        ("0", "0", "0"),
        description="Disturbance torque iota(t) in body axes, expressions in t [s], i [N m].",
    )

    @model_validator(mode="after")
    def _initial_attitude(self):
        for k, x in enumerate(self.inertia):
            if not (x > 0 and math.isfinite(x)):
                raise ValueError(
                    f"inertia[{k}] = {x}: principal inertias must be finite and > 0 kg m^2"
                )
        if (self.initial_attitude_deg is None) == (self.initial_quaternion is None):
            raise ValueError(
                "give exactly one of initial_attitude_deg [deg] and initial_quaternion [-]"
            )
        if self.initial_quaternion is not None:
            for k, p in enumerate(self.initial_quaternion):
                norm = float(np.linalg.norm(p))
                if not abs(norm - 1.0) <= 1e-6:
                    raise ValueError(
                        f"initial_quaternion[{k}]: norm {norm:.9g}, a unit quaternion is needed"
                    )
        n = self.count
        if n < 1:
            raise ValueError("initial_attitude_deg / initial_quaternion: at least one spacecraft")
        if self.initial_body_rate is not None and len(self.initial_body_rate) != n:
            raise ValueError(
                f"initial_body_rate: {len(self.initial_body_rate)} rows for {n} spacecraft"
            )
        return self

    @property
    def count(self) -> int:
        rows = (
            self.initial_attitude_deg
            if self.initial_attitude_deg is not None
            else self.initial_quaternion
        )
        return len(rows or [])

    def given_quaternions(self) -> np.ndarray:
        """(N, 4) initial unit quaternions as given (Euler angles converted, quaternions normalised)."""
        if self.initial_quaternion is not None:
            p = np.asarray(self.initial_quaternion, dtype=float)
            return p / np.linalg.norm(p, axis=-1, keepdims=True)
        return np.asarray(
            _quaternion_from_euler()(np.deg2rad(np.asarray(self.initial_attitude_deg, float)))
        )

    def quaternions(self) -> np.ndarray:
        """(N, 4) initial unit quaternions of the plant's state."""
        return self.given_quaternions()

    def euler_angles(self) -> np.ndarray:
        """(N, 3) initial 3-2-1 Euler angles [rad] of the plant's state."""
        return np.asarray(_euler_from_quaternion()(self.quaternions()))


class QuaternionPlantSection(RigidBodyAttitudeSection):
    """N rigid bodies with quaternion kinematics (one principal inertia for every spacecraft)."""

    gyroscopic: bool = Field(
        True, description="Include -omega x J omega (false: the error-level form)."
    )


def quaternion_plant(
    inertia: Vec3, omega0, q0, disturbance_torque: Vec3Expr, gyroscopic: bool
) -> QuaternionRigidBodyPlant:
    """Rigid bodies of principal inertia [kg m^2] from (N, 3) body rates [rad/s] and (N, 4) quaternions
    (the one builder: also the attitude part of the ``switched-formation`` plant)."""
    from formation_ftc.components.plants.quaternion_rigid_body import QuaternionRigidBodyPlant

    return QuaternionRigidBodyPlant(
        inertia=as_float(np.diag(inertia)),
        initial_omega=as_float(omega0),
        initial_quaternion=as_float(q0),
        disturbance_torque=_vec3_text(disturbance_torque),
        gyroscopic=gyroscopic,
    )


def _quaternion_plant(sec: QuaternionPlantSection, ctx: BuildContext):
    n = sec.count
    w0 = (
        np.zeros((n, 3))
        if sec.initial_body_rate is None
        else np.asarray(sec.initial_body_rate, float)
    )
    return quaternion_plant(
        sec.inertia, w0, sec.quaternions(), sec.disturbance_torque, sec.gyroscopic
    )


register_component_type(
    "plant",
    QUATERNION_PLANT,
    QuaternionPlantSection,
    _quaternion_plant,
    "rigid-body attitudes with quaternion kinematics, driven by body torques (Yang2013 (4))",
)

_PITCH_LIMIT_DEG = float(np.rad2deg(SINGULAR_PITCH_LIMIT_RAD))


class EulerAnglePlantSection(StrictModel):
    """m rigid bodies in 3-2-1 Euler angles driven by generalised torques (Mehrabian (1), (27)-(28)):
    true inertias drawn about ``inertia``, random or given initial angles, a Gaussian input disturbance
    held over each step; every draw from the run seed. Defaults: the paper's data and our choices
    (E003-10)."""

    count: int = Field(8, ge=1, le=64, description="Number m of spacecraft [-].")
    inertia: Vec3 = Field(
        NOMINAL_INERTIA,
        description="Principal inertia diag(...) about which every spacecraft's true inertia is drawn "
        "[kg m^2], each > 0 (default 20, 18, 15 kg m^2, our choice E003-10; an attitude law's "
        "model is stated in its own section).",
    )
    inertia_uncertainty: float = Field(
        0.1,
        ge=0.0,
        lt=1.0,
        description="True J = diag(inertia) diag(1 + delta), delta ~ U[-u, u]^3 per spacecraft, drawn "
        "from the run seed [-] (paper: +-10 %).",
    )
    random_initial_attitude: bool = Field(
        True,
        description="Draw every initial Euler angle from U[initial_attitude_range_deg] with the run seed "
        "(inside the run, so a campaign varies it through the seed); false: initial_attitude_deg.",
    )
    initial_attitude_range_deg: tuple[float, float] = Field(
        (0.0, 60.0), description="Range of the random initial Euler angles [deg] (paper: 0..60)."
    )
    initial_attitude_deg: list[Vec3] | None = Field(
        None,
        description="Initial [theta (pitch), phi (roll), psi (yaw)] per spacecraft [deg] (used when "
        "random_initial_attitude = false).",
    )
    initial_rate_deg_s: list[Vec3] | None = Field(
        None,
        description="Initial Euler-angle rates per spacecraft [deg/s] (default 0, our choice).",
    )
    disturbance_variance: float = Field(
        0.001,
        ge=0.0,
        description="Variance of the Gaussian input disturbance d_j, i.i.d. per spacecraft and channel, "
        "held over each step [(N m)^2] (paper: 0.001).",
    )

    @model_validator(mode="after")
    def _check(self):
        for k, x in enumerate(self.inertia):
            if not (x > 0 and math.isfinite(x)):
                raise ValueError(
                    f"inertia[{k}] = {x}: principal inertias must be finite and > 0 kg m^2"
                )
        lo, hi = self.initial_attitude_range_deg
        if not lo <= hi:
            raise ValueError(
                f"initial_attitude_range_deg = [{lo}, {hi}]: lower bound must be <= upper bound"
            )
        if self.random_initial_attitude and max(abs(lo), abs(hi)) >= _PITCH_LIMIT_DEG:
            raise ValueError(
                f"initial_attitude_range_deg = [{lo}, {hi}] deg can draw a pitch at or beyond "
                f"+-{_PITCH_LIMIT_DEG:.0f} deg: the Euler-angle EL model is singular at theta = +-90 deg "
                "(R_bar has 1/cos(theta), E003-08); use a range inside "
                f"(-{_PITCH_LIMIT_DEG:.0f}, {_PITCH_LIMIT_DEG:.0f}) deg"
            )
        if not self.random_initial_attitude:
            if self.initial_attitude_deg is None:
                raise ValueError(
                    "initial_attitude_deg is required when random_initial_attitude = false"
                )
            check_away_from_singularity(
                np.deg2rad(np.asarray(self.initial_attitude_deg, dtype=float)),
                field="initial_attitude_deg",
            )
        for name in ("initial_attitude_deg", "initial_rate_deg_s"):
            rows = getattr(self, name)
            if rows is not None and len(rows) != self.count:
                raise ValueError(f"{name}: {len(rows)} rows for {self.count} spacecraft")
        return self


def _euler_angle_plant(sec: EulerAnglePlantSection, ctx: BuildContext):
    from formation_ftc.components.plants.euler_angle_attitude import EulerAngleAttitudePlant

    m = sec.count

    def rows(v):
        return np.zeros((m, 3)) if v is None else np.deg2rad(np.asarray(v, dtype=float))

    return EulerAngleAttitudePlant(
        seed=np.asarray(ctx.scenario.simulation.seed, dtype=np.uint32),
        random_initial=as_float(1.0 if sec.random_initial_attitude else 0.0),
        q0_range=as_float(np.deg2rad(sec.initial_attitude_range_deg)),
        q0_fixed=as_float(rows(sec.initial_attitude_deg)),
        qdot0=as_float(rows(sec.initial_rate_deg_s)),
        J_nominal=as_float(np.tile(np.asarray(sec.inertia), (m, 1))),
        inertia_spread=as_float(sec.inertia_uncertainty),
        disturbance_std=as_float(np.sqrt(sec.disturbance_variance)),
        step=ctx.dt,
    )


register_component_type(
    "plant",
    EULER_PLANT,
    EulerAnglePlantSection,
    _euler_angle_plant,
    "rigid-body attitudes in 3-2-1 Euler angles driven by generalised torques, drawn inertias, held "
    "input noise (Mehrabian (1), (27)-(28))",
)


def _needs_quaternion_plant(slot: str, name: str, ctx: BuildContext) -> None:
    plant = ctx.scenario.type_of("plant")
    if plant not in QUATERNION_PLANTS:
        raise CompositionError(
            f"{slot} {name} converts a quaternion attitude, but plant {plant} has none "
            f"(use it with plant {' or '.join(sorted(QUATERNION_PLANTS))})"
        )


# ----------------------------------------------------------------------------------------- sensors
class QuaternionEulerSection(StrictModel):
    """Exact measurement; no fields."""


def _quaternion_euler(sec: QuaternionEulerSection, ctx: BuildContext):
    from formation_ftc.components.sensors.quaternion_euler import QuaternionToEulerSensors

    _needs_quaternion_plant("sensors", EULER_SENSORS, ctx)
    return QuaternionToEulerSensors(count=ctx.count)


register_component_type(
    "sensors",
    EULER_SENSORS,
    QuaternionEulerSection,
    _quaternion_euler,
    "attitude as 3-2-1 Euler angles [theta, phi, psi] and body rates, from a quaternion plant",
)


# -------------------------------------------------------------------------------------- actuators
class FaultEntry(StrictModel):
    spacecraft: int = Field(ge=1, description="Faulty spacecraft (1-based) [-].")
    channel: int = Field(
        ge=1, le=3, description="Faulty generalised channel 1 = pitch, 2 = roll, 3 = yaw [-]."
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
            raise ValueError(f"end = {self.end} s must be >= start = {self.start} s")
        return self


class EulerAllocationSection(StrictModel):
    """tau_body = R_bar(q)^T (tau_gen + u_bar), u_bar the additive faults held over each step (on the
    Euler-angle plant, whose input is the generalised torque: tau_gen + u_bar, Mehrabian (2))."""

    faults: list[FaultEntry] = Field(
        default_factory=list, description="Additive faults in the law's generalised channels [N m]."
    )


def _fault_data(sec: EulerAllocationSection, ctx: BuildContext):
    for k, f in enumerate(sec.faults):
        if f.spacecraft > ctx.count:
            raise CompositionError(
                f"actuator.faults[{k}].spacecraft = {f.spacecraft}: plant {ctx.scenario.type_of('plant')} "
                f"has {ctx.count} spacecraft"
            )
    statics = dict(
        torques=tuple(str(f.torque) for f in sec.faults),
        spacecraft=tuple(f.spacecraft - 1 for f in sec.faults),
        channels=tuple(f.channel - 1 for f in sec.faults),
        step=ctx.dt,
    )
    windows = as_float(np.array([(f.start, f.end) for f in sec.faults], dtype=float).reshape(-1, 2))
    return statics, windows


def _euler_allocation(sec: EulerAllocationSection, ctx: BuildContext):
    from formation_ftc.components.actuators.additive_faults import HeldAdditiveFaultActuator
    from formation_ftc.components.actuators.euler_torque_allocation import EulerTorqueAllocation
    from formation_ftc.sim.components import IdealActuator

    if ctx.scenario.type_of("plant") == EULER_PLANT:  # driven by the generalised torque: no mapping
        statics, windows = _fault_data(sec, ctx)
        return HeldAdditiveFaultActuator(count=ctx.count, windows=windows, **statics)
    _needs_quaternion_plant("actuator", EULER_ALLOCATION, ctx)
    if not sec.faults:
        return EulerTorqueAllocation(inner=IdealActuator())
    statics, windows = _fault_data(sec, ctx)
    return EulerTorqueAllocation(
        inner=HeldAdditiveFaultActuator(count=ctx.count, windows=windows, **statics)
    )


register_component_type(
    "actuator",
    EULER_ALLOCATION,
    EulerAllocationSection,
    _euler_allocation,
    "generalised (Euler-angle) torque + additive faults -> body torque R_bar(q)^T (...) "
    "(unmapped on the Euler-angle plant)",
)


# -------------------------------------------------------------------------------------- estimators
class IsolationEntry(StrictModel):
    spacecraft: int = Field(ge=1, description="True faulty spacecraft (1-based) [-].")
    channel: int = Field(ge=1, le=3, description="True faulty channel [-].")
    reported_spacecraft: int = Field(ge=1, description="Spacecraft the FDI blames (1-based) [-].")
    reported_channel: int = Field(ge=1, le=3, description="Channel the FDI blames [-].")


class ScriptedFdiSection(StrictModel):
    """FDI report (flag, u*) of the actuator's faults with imperfections."""

    detected: bool = Field(True, description="False models a missed detection.")
    delay: float = Field(
        5.0, ge=0.0, description="Detection latency; the estimate also lags by it [s]."
    )
    scale: float = Field(
        1.0, description="Identification scale error: u* = scale u_bar(t - delay) + bias [-]."
    )
    bias: float = Field(0.0, description="Identification bias while the fault is seen [N m].")
    noise_std: float = Field(
        0.0, ge=0.0, description="Std of a per-step Gaussian identification noise [N m]."
    )
    isolation: list[IsolationEntry] = Field(
        default_factory=list, description="Isolation errors: report a true fault elsewhere."
    )


def _scripted_fdi(sec: ScriptedFdiSection, ctx: BuildContext):
    from formation_ftc.blocks.fdi import fdi_params, isolation_routing
    from formation_ftc.components.estimators.fdi_imperfections import ScriptedFdi

    act = ctx.section("actuator")
    if ctx.scenario.type_of("actuator") != EULER_ALLOCATION or not act.faults:
        raise CompositionError(
            f"estimator {SCRIPTED_FDI} reports the faults of the actuator, but actuator "
            f"{ctx.scenario.type_of('actuator')} has no faults (give actuator {EULER_ALLOCATION} "
            "with faults)"
        )
    statics, windows = _fault_data(act, ctx)
    m, nch = ctx.count, 3
    mask = np.zeros((m, nch))
    for f in act.faults:
        mask[f.spacecraft - 1, f.channel - 1] = 1.0
    faulty = {(f.spacecraft, f.channel) for f in act.faults}
    moves = {}
    for k, e in enumerate(sec.isolation):
        if (e.spacecraft, e.channel) not in faulty:
            raise ValueError(
                f"estimator.isolation[{k}]: spacecraft {e.spacecraft} channel {e.channel} has no fault"
            )
        if max(e.spacecraft, e.reported_spacecraft) > m:
            raise ValueError(f"estimator.isolation[{k}]: spacecraft numbers must be in 1..{m}")
        moves[(e.spacecraft - 1, e.channel - 1)] = (
            e.reported_spacecraft - 1,
            e.reported_channel - 1,
        )
    params = fdi_params(
        m,
        nch,
        fault_mask=mask,
        onset=min(f.start for f in act.faults),
        delay=sec.delay,
        detected=sec.detected,
        scale=sec.scale,
        bias=sec.bias,
        noise_std=sec.noise_std,
        routing=isolation_routing(m, nch, moves),
    )
    seed = np.asarray(ctx.scenario.simulation.seed, dtype=np.uint32)
    statics.pop("step")  # the FDI reads the step from its flight inputs
    return ScriptedFdi(count=m, seed=seed, windows=windows, params=params, **statics)


register_component_type(
    "estimator",
    SCRIPTED_FDI,
    ScriptedFdiSection,
    _scripted_fdi,
    "scripted FDI report (flag, u*) of the actuator's faults: latency, missed detection, "
    "isolation and identification errors",
)


# ------------------------------------------------------------------------------------- controllers
class NetworkedElHinfSection(StrictModel):
    """Distributed H-infinity synchronisation / tracking law with adaptive fault recovery (Euler angles)."""

    #: fields whose NetworkedElHinfController attribute has another name (campaign.binding)
    leaf_paths: ClassVar[dict[str, str]] = {"boundary_layer": "phi_b"}
    edges: list[tuple[int, int]] = Field(
        description="Undirected links as 1-based spacecraft pairs, unit weights [-]; "
        "the graph must be connected."
    )
    law: Literal["literal", "diffusive"] = Field(
        "literal", description="Reading of the synchronisation law."
    )
    compensation: Literal["sat", "sign", "certainty_equivalence"] = Field(
        "sat", description="Fault compensation Gamma: sat(s/phi_b) u^, sgn(s) u^ or -u^."
    )
    gamma: float = Field(0.6, gt=0.0, description="H-infinity level gamma_j [-].")
    alpha: float = Field(0.86, description="Synchronisation weight alpha_j [-].")
    K: float = Field(20.0, description="K_j = K I_3 [N m s].")
    K_P: float = Field(0.16, description="Proportional gain K_P I_3 [1/s].")
    K_I: float = Field(0.001, description="Integral gain K_I I_3 [1/s^2].")
    sigma: float = Field(0.5, gt=0.0, description="Adaptation gain sigma I_3 [N m / rad].")
    e_gain: float = Field(1.0, gt=0.0, description="Estimate pull towards the FDI estimate [1/s].")
    boundary_layer: float = Field(0.01, gt=0.0, description="Width phi_b of sat(s/phi_b) [rad/s].")
    nominal_inertia: Vec3 = Field(
        NOMINAL_INERTIA,
        description="Principal inertia of the law's model, known on "
        "board [kg m^2] (default 20, 18, 15 kg m^2, "
        "Mehrabian's nominal J^, a stated value: never the "
        "plant's true inertia).",
    )
    desired_attitude: Vec3Expr = Field(
        ("0", "0", "0"),
        description="Desired [theta, phi, psi] per spacecraft, expressions in t [s], i [rad].",
    )

    @model_validator(mode="after")
    def _check(self):
        if not self.edges:
            raise ValueError("edges: at least one link is needed")
        for k, (a, b) in enumerate(self.edges):
            if a < 1 or b < 1 or a == b:
                raise ValueError(
                    f"edges[{k}] = [{a}, {b}]: 1-based spacecraft numbers, no self-loops"
                )
        if any(not x > 0 for x in self.nominal_inertia):
            raise ValueError(
                f"nominal_inertia = {self.nominal_inertia}: every entry must be > 0 kg m^2"
            )
        return self


def _attitude_chain_fits(ctx: BuildContext) -> None:
    """The Euler-angle law on a quaternion plant needs the Euler sensors and the torque allocation."""
    s = ctx.scenario
    plant = s.type_of("plant")
    if plant not in QUATERNION_PLANTS:
        return  # other plants: the loop's own checks (quantities, counts) apply
    if s.type_of("sensors") != EULER_SENSORS:
        raise CompositionError(
            f"controller {EULER_LAW} reads 3-2-1 Euler angles, but plant {plant} has a quaternion "
            f"attitude and sensors {s.type_of('sensors') or '(none: the raw plant state)'} do not convert it "
            f'(use sensors type = "{EULER_SENSORS}")'
        )
    if s.type_of("actuator") != EULER_ALLOCATION and not getattr(
        ctx.section("actuator"), "euler_allocation", False
    ):
        raise CompositionError(
            f"controller {EULER_LAW} commands a generalised torque conjugate to the Euler angles, but plant "
            f"{plant} is driven by a body torque and actuator {s.type_of('actuator') or '(ideal)'} "
            f'does not map one to the other (use actuator type = "{EULER_ALLOCATION}", or one with '
            "euler_allocation = true)"
        )
    # the law's model is singular at pitch +-90 deg: start well away from it
    check_away_from_singularity(
        ctx.section("plant").euler_angles(), field="plant initial attitude (3-2-1 Euler angles)"
    )


def _networked_el_hinf(sec: NetworkedElHinfSection, ctx: BuildContext):
    from formation_ftc.components.controllers.networked_el_hinf import NetworkedElHinfController

    _attitude_chain_fits(ctx)
    quantity = getattr(ctx.plant, "quantity", "torque")
    if quantity != "torque":
        raise CompositionError(
            f"controller {EULER_LAW} (NetworkedElHinfController) is an attitude law commanding a "
            f"torque, but plant {ctx.scenario.type_of('plant')} ({type(ctx.plant).__name__}) is "
            f"driven by a {quantity}: use an attitude plant"
        )
    m = ctx.count
    for k, (a, b) in enumerate(sec.edges):
        if a > m or b > m:
            raise CompositionError(
                f"controller.edges[{k}] = [{a}, {b}]: plant {ctx.scenario.type_of('plant')} "
                f"has {m} spacecraft"
            )
    A = graphs.adjacency(m, [(a - 1, b - 1) for a, b in sec.edges], directed=False)
    if not graphs.is_connected_undirected(A):
        raise ValueError(
            "controller.edges: the communication graph is not connected; the synchronisation law "
            "needs a connected undirected graph"
        )
    J = sec.nominal_inertia  # stated on board, never the plant's inertia
    ones = np.ones((m, 3))
    pj, pn = np.nonzero(np.triu(A > 0, 1))
    return NetworkedElHinfController(
        count=m,
        K=as_float(sec.K * ones),
        K_P=as_float(sec.K_P * ones),
        K_I=as_float(sec.K_I * ones),
        sigma=as_float(sec.sigma * ones),
        e_gain=as_float(sec.e_gain * ones),
        alpha=as_float(sec.alpha * np.ones(m)),
        gamma=as_float(sec.gamma * np.ones(m)),
        phi_b=as_float(sec.boundary_layer),
        avg=as_float(graphs.row_normalized(A)),
        J_hat=as_float(np.stack([np.diag(J)] * m)),
        law=sec.law,
        compensation=sec.compensation,
        desired_attitude=_vec3_text(sec.desired_attitude),
        links=tuple((int(a), int(b)) for a, b in zip(pj, pn, strict=True)),
    )


register_component_type(
    "controller",
    EULER_LAW,
    NetworkedElHinfSection,
    _networked_el_hinf,
    "Mehrabian distributed H-infinity attitude synchronisation with adaptive fault recovery "
    "(3-2-1 Euler angles, generalised torque)",
)


# ------------------------------------------------------------------------------------- evaluation
class MehrabianMetricsSection(StrictModel):
    """Mehrabian's metric set over three windows (fault window, whole run, assessment window), clipped
    to the horizon; a window that starts after the horizon yields no metrics."""

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
                raise ValueError(f"{name} = [{a}, {b}]: need 0 <= start < end [s]")
        return self


def metric_windows(scenario: Any) -> dict[str, tuple[float, float]] | None:
    """The windows [s] of a composed scenario's ``mehrabian-metrics`` evaluation (fault window, run,
    assessment window), clipped to the horizon; None without one.

    Parameters
    ----------
    scenario : ComposedScenario
        A validated composed scenario.

    Returns
    -------
    dict or None
        ``{"fault_window": (a, b), "run": (0, H), "assessment_window": (a, b)}`` [s].
    """
    sec = next((v for n, v in scenario._evaluation_sections if n == MEHRABIAN_METRICS), None)
    return None if sec is None else _clipped_windows(sec, float(scenario.simulation.horizon))


def _clipped_windows(sec: MehrabianMetricsSection, H: float) -> dict[str, tuple[float, float]]:
    raw = {
        "fault_window": sec.fault_window,
        "run": (0.0, H),
        "assessment_window": sec.assessment_window,
    }
    return {w: (min(float(a), H), min(float(b), H)) for w, (a, b) in raw.items()}


class _Opts(TypedDict, total=False):
    """Keyword arguments of :class:`Metric` that vary between the rows of a metric table."""

    norm: bool
    square: bool
    component: int


def _mehrabian_metrics(sec: MehrabianMetricsSection, ctx: BuildContext) -> None:
    """Per window: RMS synchronisation / tracking error and RMS control (integrated at the RK stages)
    [rad, N m], effort int sum_j |u_j|^2 dt [(N m)^2 s]; maxima over the step starts t_k in the window of
    the largest link / tracking error norm, the spread (max - min over spacecraft) and |angle| per Euler
    angle [rad]. Declares metrics only (no evaluation component)."""
    from formation_ftc.components.plants.euler_angle_attitude import AXES
    from formation_ftc.sim.metrics import Metric

    if ctx.scenario.type_of("controller") != EULER_LAW or ctx.plant.quantity != "torque":
        raise CompositionError(
            f"evaluation {MEHRABIAN_METRICS} scores the tracking and synchronisation errors of "
            f"controller {EULER_LAW}, but the loop has controller {ctx.scenario.type_of('controller')}"
        )
    if not any(s.name == "attitude" for s in ctx.plant.signals()):
        raise CompositionError(
            f"evaluation {MEHRABIAN_METRICS} reads the plant's Euler angles (attitude), but plant "
            f"{ctx.scenario.type_of('plant')} records none (use plant {EULER_PLANT})"
        )
    dt = ctx.dt
    rms = _Opts(norm=True, square=True)  # RK-stage integrals of |.|^2
    # (name, signal, reduction, window kind, options, spacecraft reduction, units); window kind
    # "stage": integrated over [a, b) at the RK stages, "sample": the step starts t_k in [a, b)
    table: list[tuple[str, str, str, str, _Opts, str, str]] = [
        ("sync_err_rms", "synchronisation_error", "stage_root_mean", "stage", rms, "mean", "rad"),
        ("track_err_rms", "tracking_error", "stage_root_mean", "stage", rms, "mean", "rad"),
        ("control_effort", "command", "stage_integral", "stage", rms, "sum", "N2 m2 s"),
        ("control_rms", "command", "stage_root_mean", "stage", rms, "mean", "N m"),
        ("sync_err_max", "synchronisation_error", "max", "sample", _Opts(norm=True), "max", "rad"),
        ("track_err_max", "tracking_error", "max", "sample", _Opts(norm=True), "max", "rad"),
        *(
            (f"spread_max_{ax}", "attitude", "max", "sample", _Opts(component=p), "range", "rad")
            for p, ax in enumerate(AXES)
        ),
        *(
            (
                f"abs_max_{ax}",
                "attitude",
                "max",
                "sample",
                _Opts(component=p, norm=True),
                "max",
                "rad",
            )
            for p, ax in enumerate(AXES)
        ),
    ]
    for w, (a, b) in _clipped_windows(sec, ctx.horizon).items():
        if b - a <= 0:  # window after the horizon (shortened run): no metrics
            continue
        ends = {"stage": as_float(b), "sample": as_float(b - 0.5 * dt)}  # sample: a <= t_k < b
        ctx.metrics.extend(
            Metric(
                f"{name}_{w}",
                signal,
                reduce,
                spacecraft=sc,
                units=units,
                start=as_float(a),
                end=ends[kind],
                **opts,
            )
            for name, signal, reduce, kind, opts, sc, units in table
        )


register_component_type(
    "evaluation",
    MEHRABIAN_METRICS,
    MehrabianMetricsSection,
    _mehrabian_metrics,
    "Mehrabian's metrics: synchronisation / tracking error, effort, Euler-angle spreads per window",
)
