"""Catalog: the iterative learning observer (ILO) and the learning / conventional output-feedback
formation-keeping laws (LOF2TC, COF2TC) of Gui et al. 2022, for composed scenarios on any
translational plant with an (N, 6) relative state; Gui2022's own plant (``clohessy-wiltshire-zoh``:
linear CW deputies driven by accelerations, stepped exactly, with the perturbation d(t) of its
ref. [12]) and its evaluation (``gui2022-scores``: the signals and metric set of its Sec. 5).

How the flight side's CW design meets a plant it was not designed for:

* **On-board model.** The ILO's internal model and the laws' nominal orbit q0(t) are the linear
  Clohessy-Wiltshire equations with a mean motion ``mean_motion`` [rad/s] (default: the mean motion
  sqrt(mu / a^3) of the ``[reference]`` orbit, known on board; required without one). On a nonlinear plant about an
  elliptic reference (``plant.type = "relative-lvlh"``) the difference between the true relative
  acceleration and the CW model -- eccentricity, nonlinearity, and the plant's disturbance -- enters
  the ILO as an unknown input in the velocity channel, exactly where the thruster faults enter (H = B):
  the fault estimate F_hat reconstructs the fault *plus* that model mismatch.
* **Acceleration -> force.** The laws and the ILO work in accelerations [m/s^2]. On a force-driven
  plant the law's command is scaled by the nominal masses known on board,
  ``f_i = m_i^nom u_i`` [N] (:mod:`~formation_ftc.components.controllers.acceleration_to_force`), and the
  ILO's time update divides the loop's force command by the same masses, ``u_i = f_i / m_i^nom``
  (:mod:`~formation_ftc.components.estimators.acceleration_model`). ``nominal_mass`` defaults to
  100 kg each (a stated nominal value, never the plant's masses); a value other than the true masses
  acts like an actuator-gain error. The ILO starts from its stated ``initial_estimate`` (default zero).
* **Gains.** ``gains = "printed"`` uses the L1, L2 / K given in the section (the paper's printed gains,
  designed at its own mean motion); ``gains = "lmi"`` (observer) re-solves the LMIs (8), (27) and the
  pole-region LMI at the on-board mean motion (``lmi_scale``: the free scale of these homogeneous
  LMIs), ``gains = "care"`` (law) the CARE (34) with Q = care_q_scale I6, R = I3.
* **Fault in acceleration units.** With a ``thruster-bias`` actuator the loop records
  ``fault_acceleration`` = F_i / m_i (the true fault per unit true mass) and ``fault_error`` =
  fault_acceleration - F_hat [m/s^2]; the laws add ``position_tracking_error`` and
  ``velocity_tracking_error`` (norms of the measured tracking error e_y).

The ILO on a plant without an (N, 6) relative state (an attitude plant) or behind sensors that do not
measure it is rejected at validation, naming both parts; so is a law on a torque-driven plant.
"""

from __future__ import annotations

import functools
import math
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from formation_ftc.config.base import StrictModel
from formation_ftc.methods.composed import (
    BuildContext,
    InitialStateRows,
    per_spacecraft,
    register_component_type,
    require_slot,
)
from formation_ftc.sim.contract import CompositionError, as_float

if TYPE_CHECKING:
    from formation_ftc.components.plants.clohessy_wiltshire_zoh import ZohClohessyWiltshirePlant

__all__ = [
    "ILO",
    "LOF2TC",
    "COF2TC",
    "ZOH_CW",
    "SCORES",
    "IloSection",
    "Lof2tcSection",
    "Cof2tcSection",
    "ZohCwPlantSection",
    "ScoresSection",
    "onboard_mean_motion",
    "nominal_mass_of",
    "ilo_lmi_design",
    "care_solution",
    "lowpass_steps",
    "LOWPASS_WINDOW",
    "ESTIMATE_ERROR_AT",
]

ILO = "iterative-learning-observer"
LOF2TC = "gui2022-lof2tc"
COF2TC = "gui2022-cof2tc"
ZOH_CW = "clohessy-wiltshire-zoh"
SCORES = "gui2022-scores"
#: sensors that deliver the (N, 6) relative state y = q the ILO and the laws need (C = I6)
STATE_SENSORS = (None, "relative-state", "lvlh-relative-state")
#: the flight side's nominal on-board mass when a scenario states none [kg] (``nominal_mass``)
NOMINAL_MASS = 100.0
#: boxcar of the low-pass metrics of ``gui2022-scores`` [s]: F - F_hat (and v - h) averaged over
#: consecutive blocks of this length before the RMS (``block_rms``); the deviation of F_hat from its
#: block mean measures the chatter (``block_dev_rms``). Fixed, independent of ``simulation.record_every``.
LOWPASS_WINDOW = 0.1
#: times [s] of the exact samples ``estimate_pos_err_at_<t>s`` of ||q - q_hat|| (position part)
ESTIMATE_ERROR_AT = (0.0, 1.0, 2.0)

VEC = ("spacecraft", "axis")
SC = ("spacecraft",)
ACC = "m s-2"
Vec3 = tuple[float, float, float]
Vec6 = tuple[float, float, float, float, float, float]
_ONBOARD_MEAN_MOTION = (
    "Mean motion n of the on-board CW model [rad/s] (default: sqrt(mu / a^3) of the reference orbit; "
    "required without one)."
)


def _matrix(value, shape, field: str):
    if value is None:
        return None
    arr = np.asarray(value, dtype=float)
    if arr.shape != shape:
        raise ValueError(
            f"{field}: expected a {shape[0]}x{shape[1]} matrix (list of rows), got shape {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{field}: entries must be finite")
    return arr.tolist()


def _on_grid(tau: float, dt: float, field: str) -> int:
    from formation_ftc.blocks.observers.iterative_learning_observer import (
        LearningIntervalError,
        learning_steps,
    )

    try:
        return learning_steps(tau, dt, field)
    except LearningIntervalError as exc:
        raise ValueError(str(exc)) from None


def lowpass_steps(dt: float) -> int:
    """Steps of the low-pass boxcar: LOWPASS_WINDOW / dt [s / s] rounded to an even number >= 2 (an
    even boxcar removes a chatter of period 2 steps exactly)."""
    return max(2, 2 * round(LOWPASS_WINDOW / dt / 2))


# ------------------------------------------------------------------------------- shared decisions
def onboard_mean_motion(given: float | None, scenario: Any, slot: str) -> float:
    """The mean motion of the on-board CW model [rad/s]: ``given``, else sqrt(mu / a^3) of the
    composed ``scenario``'s ``[reference]`` orbit (known on board); never the plant's (truth)."""
    if given is not None:
        return float(given)
    ref = scenario.section("reference")
    if ref is not None and hasattr(ref, "semi_major_axis"):
        return math.sqrt(ref.mu / ref.semi_major_axis**3)
    raise CompositionError(
        f"{slot} {scenario.type_of(slot)}: its CW model needs a mean motion, but the loop "
        f"has no [reference] orbit to take it from (give {slot}.mean_motion [rad/s]; the "
        f"plant's orbit is truth the flight side does not read)"
    )


def _relative_state(ctx: BuildContext, slot: str) -> None:
    """A CompositionError naming both parts unless the plant has an (N, 6) relative state that the
    sensors deliver."""
    plant, name = ctx.plant, ctx.scenario.type_of(slot)
    plant_name = ctx.scenario.type_of("plant")
    shapes = ctx.sensed_shapes() or {}  # what sensors see
    if shapes.get("q") != (ctx.count, 6) or getattr(plant, "quantity", "force") not in (
        "force",
        "acceleration",
    ):
        keys = ", ".join(sorted(shapes)) or "none"
        raise CompositionError(
            f"{slot} {name} works on the (N, 6) relative position/velocity state of a CW model, but plant "
            f"{plant_name} ({type(plant).__name__}, driven by a {getattr(plant, 'quantity', '?')}) has no such state "
            f"(state: {keys}); use a translational plant (clohessy-wiltshire, relative-lvlh)"
        )
    sensors = ctx.scenario.type_of("sensors")
    if sensors not in STATE_SENSORS:
        raise CompositionError(
            f"{slot} {name} needs the measured (N, 6) relative state (sensors relative-state or lvlh-relative-state), "
            f"but sensors {sensors} deliver something else"
        )


def nominal_mass_of(given, ctx: BuildContext, slot: str) -> np.ndarray:
    """The flight side's nominal masses [kg]: ``given``, else :data:`NOMINAL_MASS` (100 kg) each; never
    the plant's true masses."""
    field = f"{slot}.nominal_mass"
    arr = per_spacecraft(NOMINAL_MASS if given is None else given, ctx.count, field)
    if not np.all(np.isfinite(arr) & (arr > 0)):
        raise ValueError(f"{field}: every mass must be finite and > 0 kg")
    return arr


@functools.lru_cache(maxsize=16)
def ilo_lmi_design(n: float, lam: float, center: float, radius: float):
    """The ILO design (P, Y, L1, L2) of the LMIs (8), (27) and the pole region S(c, r) on the CW model
    of mean motion n [rad/s] (C = I6, H = B), normalised P >= I; cached by input (an offline design).
    Returns an :class:`~formation_ftc.design.lmi.IloLmiDesign`."""
    from formation_ftc.core.dynamics.cw import cw_matrices
    from formation_ftc.design.lmi import design_ilo_gains

    A, B = cw_matrices(n)
    return design_ilo_gains(A, np.eye(6), B, lam=lam, disk_center=center, disk_radius=radius)


@functools.lru_cache(maxsize=16)
def care_solution(n: float, q_scale: float):
    """The CARE (34) with Q = q_scale I6, R = I3 on the CW model of mean motion n [rad/s] (K = B^T P1);
    cached. Returns a :class:`~formation_ftc.design.riccati.CareSolution`."""
    from formation_ftc.core.dynamics.cw import cw_matrices
    from formation_ftc.design.riccati import solve_care

    A, B = cw_matrices(n)
    return solve_care(A, B, q_scale * np.eye(6), np.eye(3))


# ------------------------------------------------------------------------------------------ plant
class ZohCwPlantSection(InitialStateRows):
    """Deputies on linear CW dynamics driven by accelerations, stepped exactly (Gui2022 (1)-(3))."""

    mean_motion: float = Field(
        gt=0, description="Mean motion n of the chief's circular orbit [rad/s] (truth)."
    )
    initial_position: list[Vec3] = Field(description="Initial LVLH position per spacecraft [m].")
    initial_velocity: list[Vec3] | None = Field(
        None, description="Initial LVLH velocity per spacecraft [m/s] (default 0)."
    )
    disturbance_amplitude: float = Field(
        0.0,
        ge=0,
        description=(
            "A0 of d(t) = A0 [1 - 1.5 sin nt, 0.5 sin 2nt, sin nt] (Gui2022's ref. [12]) [m/s^2]; 0: none."
        ),
    )


def _zoh_cw_plant(sec: ZohCwPlantSection, ctx: BuildContext) -> ZohClohessyWiltshirePlant:
    from formation_ftc.components.plants.clohessy_wiltshire_zoh import ZohClohessyWiltshirePlant

    v0 = np.zeros((sec.count, 3)) if sec.initial_velocity is None else sec.initial_velocity
    return ZohClohessyWiltshirePlant(
        mean_motion=as_float(sec.mean_motion),
        initial_state_lvlh=as_float(np.hstack([np.asarray(sec.initial_position, float), v0])),
        disturbance_amplitude=as_float(sec.disturbance_amplitude),
    )


register_component_type(
    "plant",
    ZOH_CW,
    ZohCwPlantSection,
    _zoh_cw_plant,
    "linear CW deputies driven by accelerations, exact ZOH step, Gui2022's perturbation d(t)",
)


# ------------------------------------------------------------------------------------- estimator
class IloSection(StrictModel):
    """Iterative learning observer (5) on an on-board CW model, one per spacecraft."""

    gains: Literal["printed", "lmi"] = Field(
        "printed",
        description=(
            "'printed': L1, L2 as given; 'lmi': solve (8), (27) and the pole-region LMI at the on-board mean motion."
        ),
    )
    L1: list[list[float]] | None = Field(
        None, description="Observer gain L1 (6x6) [1/s] (gains = 'printed')."
    )
    L2: list[list[float]] | None = Field(
        None, description="Learning gain L2 (3x6) [1/s] (gains = 'printed')."
    )
    lmi_lambda: float = Field(1e-8, gt=0, description="lambda of (27) [-] (gains = 'lmi').")
    disk_center: float = Field(
        -5.0, lt=0, description="Centre c of the pole region S(c, r) [1/s] (gains = 'lmi')."
    )
    disk_radius: float = Field(
        2.0, gt=0, description="Radius r of the pole region S(c, r) [1/s] (gains = 'lmi')."
    )
    lmi_scale: float = Field(
        1.0,
        gt=0,
        description=(
            "Free scale s of the homogeneous LMIs: (P, Y, L2) -> s (P, Y, L2) after the normalised solve "
            "(P >= I) [-] (gains = 'lmi')."
        ),
    )
    Q1: Vec3 = Field(description="Diagonal of Q1, each in (0, 1] [-].")
    Q2: float = Field(gt=0, description="Learning gain Q2 [-].")
    gamma: float = Field(ge=0, description="Sign-term gain gamma [m/s^2].")
    sign_term: bool = Field(
        True, description="Include gamma sgn(e_y) (false: the ILO without the sign term)."
    )
    mu: float = Field(
        0.001, gt=0, description="mu of Theorem 1, eta = 1 + mu [-] (for `check`; Gui2022: 0.001)."
    )
    gamma1: float = Field(
        0.0193, gt=0, description="gamma_1 of (10) [-] (for `check`; Gui2022: 0.0193)."
    )
    beta: float = Field(
        1.0, gt=0, description="beta of (17), Q2 = 1/(beta eta) [-] (for `check`; Gui2022: 1)."
    )
    learning_interval: float = Field(
        gt=0, description="tau: a positive integer multiple of simulation.dt [s]."
    )
    mean_motion: float | None = Field(None, gt=0, description=_ONBOARD_MEAN_MOTION)
    nominal_mass: float | list[float] | None = Field(
        None,
        description=(
            "On-board masses m_nom [kg] dividing a force command into the model's acceleration (default: the "
            "controller's nominal_mass, else 100 kg each; never the plant's masses)."
        ),
    )
    initial_estimate: Vec6 | list[Vec6] = Field(
        (0.0,) * 6,
        description=(
            "q_hat(0), the observer's initial estimate [m, m/s]: one row for every spacecraft or one per spacecraft "
            "(default: a zero initial estimate, a stated value, never the plant's initial state)."
        ),
    )

    @model_validator(mode="before")
    @classmethod
    def _offset_moved(cls, data):
        if isinstance(data, dict) and "estimate_offset" in data:
            raise ValueError(
                "estimate_offset (q_hat(0) - y(0)) was replaced by initial_estimate, the observer's own "
                "q_hat(0) [m, m/s] (the flight side never reads the true initial state)"
            )
        return data

    @field_validator("L1")
    @classmethod
    def _l1(cls, v):
        return _matrix(v, (6, 6), "L1")

    @field_validator("L2")
    @classmethod
    def _l2(cls, v):
        return _matrix(v, (3, 6), "L2")

    @field_validator("Q1")
    @classmethod
    def _q1(cls, v):
        for k, s in enumerate(v):
            if not 0 < s <= 1:
                raise ValueError(f"Q1[{k}] = {s}: each entry must be in (0, 1]")
        return v

    @model_validator(mode="after")
    def _printed_given(self):
        if self.gains == "printed" and (self.L1 is None or self.L2 is None):
            missing = " and ".join(f for f in ("L1", "L2") if getattr(self, f) is None)
            raise ValueError(f"{missing}: required with gains = 'printed' (or set gains = 'lmi')")
        return self

    def design_at(self, n: float):
        """The LMI design (gains = 'lmi') on the CW model of mean motion n [rad/s], scaled by
        ``lmi_scale`` (an :class:`~formation_ftc.design.lmi.IloLmiDesign`)."""
        from formation_ftc.core.dynamics.cw import cw_matrices

        des = ilo_lmi_design(n, self.lmi_lambda, self.disk_center, self.disk_radius)
        if self.lmi_scale == 1.0:
            return des
        from formation_ftc.design.lmi import rescale_design

        A, B = cw_matrices(n)
        return rescale_design(des, self.lmi_scale, A, np.eye(6), B)

    def gains_at(self, n: float) -> tuple[np.ndarray, np.ndarray]:
        """(L1, L2) used on the CW model of mean motion n [rad/s]."""
        if self.gains == "printed":
            return np.asarray(self.L1, float), np.asarray(self.L2, float)
        des = self.design_at(n)
        return des.L1, des.L2


def _nominal_mass_for_estimator(sec: IloSection, ctx: BuildContext) -> np.ndarray:
    if sec.nominal_mass is not None:
        return nominal_mass_of(sec.nominal_mass, ctx, "estimator")
    ctl = ctx.section("controller")
    return nominal_mass_of(
        getattr(ctl, "nominal_mass", None)
        if ctx.scenario.type_of("controller") in (LOF2TC, COF2TC)
        else None,
        ctx,
        "estimator",
    )


def _ilo(sec: IloSection, ctx: BuildContext):
    from formation_ftc.components.estimators.acceleration_model import AccelerationModelEstimator
    from formation_ftc.components.estimators.iterative_learning_observer import (
        IterativeLearningObserver,
    )
    from formation_ftc.components.evaluations.per_unit_mass import PerUnitMass
    from formation_ftc.components.evaluations.signal_arithmetic import SignalSum

    _relative_state(
        ctx, "estimator"
    )  # the composition check only: the true initial state is not used
    m = _on_grid(sec.learning_interval, ctx.dt, "estimator.learning_interval")
    n = onboard_mean_motion(sec.mean_motion, ctx.scenario, "estimator")
    L1, L2 = sec.gains_at(n)
    N = ctx.count
    q_hat0 = np.asarray(sec.initial_estimate, dtype=float)
    if q_hat0.ndim == 1:
        q_hat0 = np.broadcast_to(q_hat0, (N, 6)).copy()
    elif q_hat0.shape != (N, 6):
        raise ValueError(
            f"estimator.initial_estimate: {q_hat0.shape[0]} rows for {N} spacecraft (give one row or {N})"
        )
    ilo = IterativeLearningObserver(
        count=N,
        mean_motion=as_float(n),
        L1=as_float(L1),
        L2=as_float(L2),
        Q1=as_float(sec.Q1),
        Q2=as_float(sec.Q2),
        gamma=as_float(sec.gamma),
        initial_estimate=as_float(q_hat0),  # stated, never the plant's initial state
        fault_prehistory=as_float(np.zeros((N, 3))),
        learning_steps=m,
        sign_term=sec.sign_term,
        mean_steps=int(ctx.scenario.simulation.record_every),
    )
    force_loop = ctx.plant.quantity == "force"
    est = (
        AccelerationModelEstimator(
            inner=ilo, nominal_mass=as_float(_nominal_mass_for_estimator(sec, ctx))
        )
        if force_loop
        else ilo
    )
    if ctx.scenario.type_of("actuator") == "thruster-bias":
        fault = "fault"
        if force_loop:
            mass = getattr(ctx.section("plant"), "mass", None)
            if mass is not None:
                ctx.evaluations.append(
                    PerUnitMass(
                        "fault_acceleration",
                        "fault",
                        mass=as_float(mass),
                        dims=VEC,
                        long_name="true thruster fault per unit true mass F_i / m_i",
                        frame="LVLH",
                    )
                )
                fault = "fault_acceleration"
        ctx.evaluations.append(
            SignalSum(
                "fault_error",
                (("+", fault), ("-", "fault_estimate")),
                dims=VEC,
                units="m s-2",
                long_name="e_F = F - F_hat (F_hat also holds the model mismatch)",
                frame="LVLH",
            )
        )
    return est


register_component_type(
    "estimator",
    ILO,
    IloSection,
    _ilo,
    "Gui2022 iterative learning observer (5): thruster-fault reconstruction on a CW model",
)


# ------------------------------------------------------------------------------------ controllers
class _OutputFeedbackSection(StrictModel):
    desired_state: list[Vec6] = Field(
        description=(
            "q0(0) of each spacecraft's nominal orbit (28), CW free motion on board [m, m/s] (one row each)."
        )
    )
    desired_motion: Literal["natural", "hold"] = Field(
        "natural",
        description=(
            "'natural': q0(t) is the CW free motion (28) from desired_state; 'hold': desired_state held fixed "
            "in LVLH (slots that are not free motion: the holding force is then an unmodelled disturbance)."
        ),
    )
    gains: Literal["printed", "care"] = Field(
        "printed",
        description=(
            "K: 'printed' as given, or 'care' = B^T P1 from the CARE (34) at the on-board mean motion."
        ),
    )
    K: list[list[float]] | None = Field(
        None, description="Gain K (3x6) [1/s^2, 1/s] (gains = 'printed')."
    )
    care_q_scale: float = Field(
        4e-5, gt=0, description="Q = care_q_scale I6 of the CARE (34) [-] (gains = 'care')."
    )
    mean_motion: float | None = Field(None, gt=0, description=_ONBOARD_MEAN_MOTION)
    nominal_mass: float | list[float] | None = Field(
        None,
        description=(
            "On-board masses m_nom [kg], f = m_nom u on a force-driven plant (default 100 kg each, a stated nominal "
            "value: never the plant's masses)."
        ),
    )

    @field_validator("K")
    @classmethod
    def _k(cls, v):
        return _matrix(v, (3, 6), "K")

    @model_validator(mode="after")
    def _printed_given(self):
        if self.gains == "printed" and self.K is None:
            raise ValueError("K: required with gains = 'printed' (or set gains = 'care')")
        return self

    def common(self, ctx: BuildContext, slot: str = "controller") -> dict:
        from formation_ftc.core.dynamics.cw import cw_matrices

        _relative_state(ctx, slot)
        N = ctx.count
        if len(self.desired_state) != N:
            raise ValueError(
                f"{slot}.desired_state: {len(self.desired_state)} rows for {N} spacecraft"
            )
        n = onboard_mean_motion(self.mean_motion, ctx.scenario, slot)
        K = (
            np.asarray(self.K, float)
            if self.gains == "printed"
            else care_solution(n, self.care_q_scale).K
        )
        _, B = cw_matrices(n)
        BpB = np.linalg.pinv(B) @ B  # B^+ H with H = B (and B^+ E with E = B)
        return dict(
            count=N,
            mean_motion=as_float(n),
            desired_initial=as_float(self.desired_state),
            K=as_float(K),
            BpH=as_float(BpB),
            hold_desired=self.desired_motion == "hold",
        )


def _on_plant(law, sec: _OutputFeedbackSection, ctx: BuildContext):
    """The acceleration law as is on an acceleration-driven plant; f = m_nom u on a force-driven one;
    any other plant keeps the law unwrapped so the loop rejects the pair naming both."""
    from formation_ftc.components.controllers.acceleration_to_force import force_from_acceleration
    from formation_ftc.components.evaluations.signal_arithmetic import PartNorm

    ctx.evaluations.extend(
        [
            PartNorm(
                "position_tracking_error",
                "tracking_error",
                0,
                3,
                dims=SC,
                units="m",
                long_name="||position part of e_y = q0 - y||",
            ),
            PartNorm(
                "velocity_tracking_error",
                "tracking_error",
                3,
                6,
                dims=SC,
                units="m s-1",
                long_name="||velocity part of e_y = q0 - y||",
            ),
        ]
    )
    if ctx.plant.quantity == "force":
        return force_from_acceleration(
            law, as_float(nominal_mass_of(sec.nominal_mass, ctx, "controller"))
        )
    return law


_FAULT_ESTIMATE = (
    'the fault estimate F_hat it compensates (e.g. type = "iterative-learning-observer")'
)


class Lof2tcSection(_OutputFeedbackSection):
    """LOF2TC (30)-(32): u = pi K e_y - B^+E v - B^+H F_hat with the learning gain pi and compensation v."""

    G1: float = Field(description="G1 of (31) [-].")
    G2: float = Field(description="G2 of (31) [s^4/m^2].")
    G3: Vec3 = Field(description="Diagonal of G3 in (32) [-].")
    G4: float = Field(description="G4 of (32) [-].")
    l: float = Field(
        1.0, gt=0, description="l of (43), G2 = 1/(l (1 + mu1)) [-] (for `check`; Gui2022: 1)."
    )
    mu1: float = Field(1e-4, gt=0, description="mu1 of Theorem 2 [-] (for `check`; Gui2022: 1e-4).")
    beta1: float = Field(
        1.0,
        gt=0,
        description="beta1 of (43), G4 = -1/(beta1 (1 + mu1)) [-] (for `check`; Gui2022: 1).",
    )
    gamma2: float = Field(
        9e-4, gt=0, description="gamma2 of (37) [-] (for `check`; Gui2022: 9e-4)."
    )
    gamma3: float = Field(
        9e-4, gt=0, description="gamma3 of (36) [-] (for `check`; Gui2022: 9e-4)."
    )
    pi_initial: float = Field(1.0, description="pi(-tau) [-].")
    v_initial: Vec3 = Field((0.0, 0.0, 0.0), description="v(-tau) [m/s^2].")
    learning_interval: float = Field(
        gt=0, description="tau of (31)-(32): a positive integer multiple of simulation.dt [s]."
    )


def _lof2tc(sec: Lof2tcSection, ctx: BuildContext):
    from formation_ftc.components.controllers.output_feedback import (
        LearningOutputFeedbackController,
    )

    require_slot(ctx, "controller", "estimator", _FAULT_ESTIMATE)
    common = sec.common(ctx)
    N = ctx.count
    law = LearningOutputFeedbackController(
        **common,
        G1=as_float(sec.G1),
        G2=as_float(sec.G2),
        G3=as_float(sec.G3),
        G4=as_float(sec.G4),
        BpE=common["BpH"],
        pi_initial=as_float(np.full(N, sec.pi_initial)),
        v_initial=as_float(np.broadcast_to(np.asarray(sec.v_initial, float), (N, 3)).copy()),
        learning_steps=_on_grid(sec.learning_interval, ctx.dt, "controller.learning_interval"),
    )
    return _on_plant(law, sec, ctx)


class Cof2tcSection(_OutputFeedbackSection):
    """COF2TC: u = K e_y, or u = K e_y - B^+H F_hat with ``fault_compensation``."""

    fault_compensation: bool = Field(
        False, description="Subtract the estimator's fault estimate F_hat."
    )


def _cof2tc(sec: Cof2tcSection, ctx: BuildContext):
    from formation_ftc.components.controllers.output_feedback import (
        ConventionalOutputFeedbackController,
    )

    if sec.fault_compensation:
        require_slot(
            ctx, "controller", "estimator", f"(with fault_compensation = true) {_FAULT_ESTIMATE}"
        )
    law = ConventionalOutputFeedbackController(
        **sec.common(ctx), fault_compensation=sec.fault_compensation
    )
    return _on_plant(law, sec, ctx)


register_component_type(
    "controller",
    LOF2TC,
    Lof2tcSection,
    _lof2tc,
    "Gui2022 LOF2TC (30)-(32): learning output feedback on a CW nominal orbit (acceleration law)",
)
register_component_type(
    "controller",
    COF2TC,
    Cof2tcSection,
    _cof2tc,
    "Gui2022 COF2TC baseline u = K e_y (optionally - F_hat) on a CW nominal orbit",
)


# ------------------------------------------------------------------------------------- evaluation
class ScoresSection(StrictModel):
    """Gui2022's evaluation signals and metric set (Sec. 5): windows of the metrics accumulated at every
    step inside the run (the fault onsets are the ``thruster-bias`` actuator's)."""

    fault_rms_delay: float = Field(
        100.0, ge=0, description="RMS of F - F_hat per axis from that axis' onset + this delay [s]."
    )
    position_rms_start: float = Field(
        1600.0, ge=0, description="RMS of ||e_pos|| (and Fig. 10's v - h, h) from this time [s]."
    )
    settle_threshold: float = Field(
        0.01, gt=0, description="|F - F_hat| threshold of the settling-time metric [m/s^2]."
    )
    estimate_start: float = Field(
        10.0, ge=0, description="max ||q - q_hat|| of the observer from this time [s] ..."
    )
    estimate_end: float = Field(
        1500.0, ge=0, description="... up to this time (before the first fault) [s]."
    )
    z_amplitude_start: float = Field(
        2100.0, ge=0, description="max |e_z| tracking error from this time [s]."
    )


def _scores_fit(ctx: BuildContext) -> None:
    """The signals ``gui2022-scores`` reads exist: the ILO's, the thruster faults, the plant's d(t)."""
    needs = {
        "estimator": (ILO, "the ILO's estimate, output error and fault estimate"),
        "actuator": ("thruster-bias", "the thruster faults F and their onsets"),
    }
    for slot, (name, what) in needs.items():
        if ctx.scenario.type_of(slot) != name:
            raise CompositionError(
                f"evaluation {SCORES} reads {what} from a {slot} {name}, but the loop's {slot} is "
                f"{ctx.scenario.type_of(slot)}"
            )
    if not any(sig.name == "disturbance" for sig in ctx.plant.signals()):
        raise CompositionError(
            f"evaluation {SCORES} reads the perturbation d of the plant (h = d + e_F), but plant "
            f"{ctx.scenario.type_of('plant')} records none (use plant {ZOH_CW})"
        )


def _scores_metrics(sec: ScoresSection, ctx: BuildContext, onset_s, law: str | None) -> list:
    """The paper's metrics, accumulated at every step k < n (final values at the horizon sample);
    ``onset_s`` the fault onsets per axis [s]."""
    from formation_ftc.sim.metrics import Metric

    sim = ctx.scenario.simulation
    dt, n_steps = ctx.dt, sim.n_steps

    def ks(t):
        return round(t / dt)

    def at(k):
        return float(k * dt)

    last = (n_steps - 0.5) * dt  # window end that excludes the horizon sample
    onset = [ks(t) for t in onset_s]
    k_rms = [k + ks(sec.fault_rms_delay) for k in onset]
    out = []
    for i, ax in enumerate("xyz"):
        err: dict[str, Any] = dict(
            signal="fault_error", component=i, norm=True, spacecraft="max", units=ACC, end=last
        )
        out += [
            Metric(f"fault_rms_err_{ax}", reduce="rms", start=at(k_rms[i]), **err),
            Metric(
                f"fault_settle_time_{ax}",
                reduce="settle_delay",
                start=at(onset[i]),
                threshold=sec.settle_threshold,
                **{**err, "units": "s"},
            ),
            Metric(
                f"fault_max_err_after_1s_{ax}", reduce="max", start=at(onset[i] + ks(1.0)), **err
            ),
            Metric(
                f"final_fault_err_{ax}",
                "fault_error",
                reduce="final",
                component=i,
                spacecraft="max",
                units=ACC,
            ),
        ]
    for c, name in enumerate(("x", "y", "z", "vx", "vy", "vz")):
        out.append(
            Metric(
                f"sign_mean_{name}",
                "estimation_error_sign",
                reduce="mean",
                component=c,
                spacecraft="mean",
                start=at(k_rms[c % 3]),
                end=last,
            )
        )
    out.append(
        Metric(
            "estimate_max_err_after_start",
            "estimation_error",
            reduce="max",
            norm=True,
            spacecraft="max",
            units="1",
            start=at(ks(sec.estimate_start)),
            end=(ks(sec.estimate_end) - 0.5) * dt,
        )
    )
    # low-pass (boxcar of lowpass_steps) RMS of F - F_hat per axis over the fault_rms window, and the RMS
    # of F_hat about its boxcar mean (the chatter) from fault_rms_delay to the x fault onset
    box = lowpass_steps(dt)
    for i, ax in enumerate("xyz"):
        out += [
            Metric(
                f"fault_lowpass_rms_err_{ax}",
                "fault_error",
                reduce="block_rms",
                component=i,
                spacecraft="max",
                units=ACC,
                start=at(k_rms[i]),
                end=last,
                block=box,
            ),
            Metric(
                f"fault_estimate_chatter_rms_{ax}",
                "fault_estimate",
                reduce="block_dev_rms",
                component=i,
                spacecraft="max",
                units=ACC,
                start=at(ks(sec.fault_rms_delay)),
                end=(onset[0] - 0.5) * dt,
                block=box,
            ),
        ]
    out += [
        Metric(
            f"estimate_pos_err_at_{tq:g}s",
            "estimation_position_error",
            reduce="at",
            spacecraft="max",
            units="m",
            start=at(ks(tq)),
        )
        for tq in ESTIMATE_ERROR_AT
        if ks(tq) <= n_steps
    ]
    if law not in (LOF2TC, COF2TC):
        return out
    pos: dict[str, Any] = dict(signal="position_tracking_error", spacecraft="max", units="m")
    out += [
        Metric("pos_rms", reduce="rms", start=at(ks(sec.position_rms_start)), end=last, **pos),
        Metric("pos_max_after_fault", reduce="max", start=at(onset[0]), end=last, **pos),
        Metric(
            "ex_max_fault_window",
            "tracking_error",
            reduce="max",
            component=0,
            norm=True,
            spacecraft="max",
            units="m",
            start=at(onset[0]),
            end=(onset[2] - 0.5) * dt,
        ),
        Metric(
            "ez_max_after",
            "tracking_error",
            reduce="max",
            component=2,
            norm=True,
            spacecraft="max",
            units="m",
            start=at(ks(sec.z_amplitude_start)),
            end=last,
        ),
        Metric(
            "pos_settle_time_0p01",
            reduce="settle",
            threshold=0.01,
            end=last,
            **{**pos, "units": "s"},
        ),
        Metric("final_pos_err", reduce="final", **pos),
        Metric(
            "final_vel_err",
            "velocity_tracking_error",
            reduce="final",
            spacecraft="max",
            units="m s-1",
        ),
    ]
    if law == LOF2TC:
        out.append(Metric("pi_max", "learning_gain", reduce="max", spacecraft="max", end=last))
        # Fig. 10: low-pass RMS per axis of v - h and of h = d + F - F_hat from position_rms_start
        for i, ax in enumerate("xyz"):
            out += [
                Metric(
                    f"{sig}_lowpass_rms_{ax}",
                    sig,
                    reduce="block_rms",
                    component=i,
                    spacecraft="max",
                    units=ACC,
                    start=at(ks(sec.position_rms_start)),
                    end=last,
                    block=box,
                )
                for sig in ("compensation_error", "synthesized_disturbance")
            ]
    return out


def _scores(sec: ScoresSection, ctx: BuildContext):
    """Gui2022's signals h = d + e_F (33), its record-interval mean, ||position part of q - q_hat|| and,
    with LOF2TC, v - h; the paper's metric set goes to ``ctx.metrics``."""
    from formation_ftc.components.evaluations.signal_arithmetic import PartNorm, SignalSum

    _scores_fit(ctx)
    law = ctx.scenario.type_of("controller")
    onsets = np.asarray(ctx.section("actuator").onset, dtype=float)
    onset_s = np.broadcast_to(onsets, (ctx.count, 3)).min(axis=0)  # earliest per axis [s]
    ctx.metrics.extend(_scores_metrics(sec, ctx, onset_s, law))
    h = (("+", "disturbance"), ("+", "fault"))
    ctx.evaluations.extend(
        [
            SignalSum(
                "synthesized_disturbance",
                (*h, ("-", "fault_estimate")),
                units=ACC,
                long_name="h = d + e_F (33)",
            ),
            SignalSum(
                "synthesized_disturbance_mean",
                (*h, ("-", "fault_estimate_mean")),
                units=ACC,
                long_name="h = d + F - mean(F_hat) over the record interval",
            ),
        ]
    )
    if law == LOF2TC:
        ctx.evaluations.append(
            SignalSum(
                "compensation_error",
                (("+", "compensation"), ("-", "synthesized_disturbance")),
                units=ACC,
                long_name="v - h, h = d + e_F (33)",
            )
        )
    return PartNorm(
        "estimation_position_error",
        "estimation_error",
        0,
        3,
        units="m",
        long_name="||q - q_hat position part|| of the ILO",
    )


register_component_type(
    "evaluation",
    SCORES,
    ScoresSection,
    _scores,
    "Gui2022 Sec. 5 signals (h = d + e_F, v - h, ||q - q_hat||) and metric set (needs the ILO, "
    "thruster-bias faults and the plant's d)",
)
