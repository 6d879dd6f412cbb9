"""Catalog: quaternion attitude laws and attitude scores for composed scenarios.

* ``controller.type = "yang2013-attitude"`` -- Yang2013's attitude law (13)
  (:class:`~formation_ftc.components.controllers._yang2013.Yang2013AttitudeController`) with
  the gains of the ``yang2013`` scenarios as defaults (K3 = 0.2, K4 = K5 = 1 [1/s], kappa = 1e-3
  [rad^2/s^2]), fed the error state (e_w, e_q, e_q4) of a fixed desired attitude in the plant's
  ``state_frame`` (inertial hold, or LVLH hold with ``state_frame = "lvlh"``) by
  :class:`~formation_ftc.components.controllers.yang2013_attitude_hold.Yang2013AttitudeHold`. It reads
  the plant state (body rate and body -> frame quaternion): the scenario has no ``[sensors]`` section;
  sensors that change the state (e.g. ``quaternion-euler``) are rejected.
* ``controller.type = "attitude-pd"`` -- quaternion PD baseline
  (:class:`~formation_ftc.components.controllers.attitude_pd.AttitudePdController`) towards a fixed
  desired attitude in the plant's state frame; no fault tolerance. Also reads the plant state.
* ``[[evaluations]] type = "attitude-scores"`` -- attitude error against a common desired attitude,
  pairwise synchronisation error and applied torque
  (:class:`~formation_ftc.components.evaluations.attitude_scores.AttitudeScores`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from pydantic import Field, model_validator

from formation_ftc.config.base import StrictModel
from formation_ftc.methods.composed import BuildContext, per_spacecraft, register_component_type
from formation_ftc.methods.composed.catalog_attitude import (
    QUATERNION_PLANTS,
    _needs_quaternion_plant,
)
from formation_ftc.sim.contract import CompositionError, as_float

if TYPE_CHECKING:
    from formation_ftc.components.controllers._yang2013 import Yang2013AttitudeController

__all__ = [
    "YANG2013_ATTITUDE",
    "ATTITUDE_PD",
    "ATTITUDE_SCORES",
    "Yang2013AttitudeSection",
    "AttitudePdSection",
    "AttitudeScoresSection",
    "yang2013_attitude_law",
]

YANG2013_ATTITUDE = "yang2013-attitude"
ATTITUDE_PD = "attitude-pd"
ATTITUDE_SCORES = "attitude-scores"

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]

#: the yang2013-attitude law's model inertia when a scenario states none [kg m^2] (``controller.inertia``):
#: the yang2013 scenarios' spacecraft
NOMINAL_INERTIA = (25.0, 25.0, 25.0)


def _state_frame(ctx: BuildContext) -> str:
    """The frame of the plant's attitude state ("inertial" for a plant that does not say)."""
    return str(getattr(ctx.section("plant"), "state_frame", "inertial"))


def _reads_plant_state(name: str, ctx: BuildContext) -> None:
    """A quaternion law reading the raw plant state: a quaternion plant and no state-changing sensors."""
    _needs_quaternion_plant("controller", name, ctx)
    sensors = ctx.scenario.type_of("sensors")
    if sensors is not None:
        raise CompositionError(
            f"controller {name} reads the plant's quaternion state (body rate, quaternion), "
            f"but sensors {sensors} replace it; leave [sensors] out (the measurement is then "
            "the plant state)"
        )


def _inertia(given: Vec3) -> np.ndarray:
    """The law's model inertia matrix from its stated principal inertia (never the plant's)."""
    return np.diag(np.asarray(given, dtype=float))


def _quaternions(rows: Quat | list[Quat] | None, n: int, field: str) -> np.ndarray:
    """One or n unit quaternions -> (n, 4) (default identity)."""
    if rows is None:
        return np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    arr = np.asarray(rows, dtype=float)
    arr = np.tile(arr, (n, 1)) if arr.ndim == 1 else arr
    if arr.shape != (n, 4):
        raise ValueError(
            f"{field}: {arr.shape[0]} quaternions for {n} spacecraft (give one or {n})"
        )
    return arr


def _unit_quaternions(value):
    if value is None:
        return value
    rows = [value] if isinstance(value, tuple) else value
    for k, p in enumerate(rows):
        norm = float(np.linalg.norm(p))
        if not abs(norm - 1.0) <= 1e-6:
            raise ValueError(
                f"quaternion {k}: norm {norm:.9g}, a unit quaternion [q1, q2, q3, q4] is needed"
            )
    return value


# ------------------------------------------------------------------------------------- yang2013
class Yang2013AttitudeSection(StrictModel):
    """Yang2013 attitude law (13), drift term cancelled, towards the state frame's axes."""

    K3: float = Field(0.2, gt=0.0, description="Angular-rate gain K3 [1/s].")
    K4: float = Field(1.0, gt=0.0, description="Quaternion-vector shaping gain K4 [1/s].")
    K5: float = Field(1.0, gt=0.0, description="Quaternion-scalar shaping gain K5 [1/s].")
    kappa: float = Field(1e-3, gt=0.0, description="Smoothing constant kappa of (13) [rad^2/s^2].")
    inertia: Vec3 = Field(
        NOMINAL_INERTIA,
        description="Principal inertia of the law's model, known on board "
        "[kg m^2] (default 25, 25, 25 kg m^2, Yang2013's spacecraft, a "
        "stated value: never the plant's true inertia).",
    )
    desired_quaternion: Quat | list[Quat] | None = Field(
        None,
        description="Desired attitude, body -> state frame, one unit quaternion [q1, q2, q3, q4] (vector "
        "first) or one per spacecraft [-] (default identity: aligned with the state frame).",
    )

    @model_validator(mode="after")
    def _check(self):
        if any(not x > 0 for x in self.inertia):
            raise ValueError(f"inertia = {self.inertia}: every entry must be > 0 kg m^2")
        _unit_quaternions(self.desired_quaternion)
        return self


def yang2013_attitude_law(
    ctx: BuildContext, inertia: Vec3, K3: float, K4: float, K5: float, kappa: float
) -> Yang2013AttitudeController:
    """Yang2013's law (13) with the stated principal inertia [kg m^2], gains K3, K4, K5 [1/s] and
    kappa [rad^2/s^2] (the one builder of the law: the catalog's Yang2013 controller types use it)."""
    from formation_ftc.components.controllers._yang2013 import Yang2013AttitudeController

    return Yang2013AttitudeController(
        count=ctx.count,
        nominal_inertia=as_float(_inertia(inertia)),
        K3=as_float(K3),
        K4=as_float(K4),
        K5=as_float(K5),
        kappa=as_float(kappa),
    )


def _yang2013_attitude(sec: Yang2013AttitudeSection, ctx: BuildContext):
    from formation_ftc.components.controllers.yang2013_attitude_hold import Yang2013AttitudeHold

    _reads_plant_state(YANG2013_ATTITUDE, ctx)
    law = yang2013_attitude_law(ctx, sec.inertia, sec.K3, sec.K4, sec.K5, sec.kappa)
    q_d = _quaternions(sec.desired_quaternion, ctx.count, "controller.desired_quaternion")
    return Yang2013AttitudeHold(law=law, desired_quaternion=as_float(q_d))


register_component_type(
    "controller",
    YANG2013_ATTITUDE,
    Yang2013AttitudeSection,
    _yang2013_attitude,
    "Yang2013 attitude law (13) on a quaternion plant's state (holds the state frame's axes)",
)


# ------------------------------------------------------------------------------------------- PD
class AttitudePdSection(StrictModel):
    """tau = -K_p sign(q_e4) q_e,v - K_d omega, q_e = q_d^* (x) q, in the plant's state frame."""

    K_p: float | list[float] = Field(
        description="Attitude gain K_p [N m] per unit error-quaternion vector (small-"
        "angle stiffness K_p / 2 [N m/rad]), one or per spacecraft, > 0."
    )
    K_d: float | list[float] = Field(
        description="Rate gain K_d [N m s], one or per spacecraft, > 0."
    )
    desired_quaternion: Quat | list[Quat] | None = Field(
        None,
        description="Desired attitude, body -> state frame, one unit quaternion [q1, q2, q3, q4] (vector "
        "first) or one per spacecraft [-] (default identity: aligned with the state frame).",
    )

    @model_validator(mode="after")
    def _unit(self):
        _unit_quaternions(self.desired_quaternion)
        return self


def _attitude_pd(sec: AttitudePdSection, ctx: BuildContext):
    from formation_ftc.components.controllers.attitude_pd import AttitudePdController

    _reads_plant_state(ATTITUDE_PD, ctx)
    n = ctx.count
    kp = per_spacecraft(sec.K_p, n, "controller.K_p")
    kd = per_spacecraft(sec.K_d, n, "controller.K_d")
    if np.any(~(kp > 0)) or np.any(~(kd > 0)):
        raise ValueError(f"controller.K_p = {list(kp)}, K_d = {list(kd)}: every gain must be > 0")
    return AttitudePdController(
        count=n,
        K_p=as_float(kp),
        K_d=as_float(kd),
        desired_quaternion=as_float(
            _quaternions(sec.desired_quaternion, n, "controller.desired_quaternion")
        ),
    )


register_component_type(
    "controller",
    ATTITUDE_PD,
    AttitudePdSection,
    _attitude_pd,
    "quaternion PD attitude baseline towards a fixed attitude in the plant's state frame, "
    "no fault tolerance",
)


# ------------------------------------------------------------------------------------ evaluation
class AttitudeScoresSection(StrictModel):
    """Attitude error, pairwise synchronisation error and applied torque against a common attitude."""

    desired_quaternion: Quat | list[Quat] | None = Field(
        None,
        description="Desired attitude body -> `frame`, one unit quaternion [q1, q2, q3, q4] (vector first) "
        "or one per spacecraft [-] (default identity).",
    )
    frame: str = Field(
        "state",
        description="Frame of desired_quaternion: 'inertial', 'lvlh' or 'state' (the "
        "plant's state_frame).",
    )

    @model_validator(mode="after")
    def _unit(self):
        _unit_quaternions(self.desired_quaternion)
        return self


def _attitude_scores(sec: AttitudeScoresSection, ctx: BuildContext):
    from formation_ftc.components.evaluations.attitude_scores import AttitudeScores

    plant = ctx.scenario.type_of("plant")
    if plant not in QUATERNION_PLANTS or ctx.plant is None or ctx.plant.quantity != "torque":
        raise CompositionError(
            f"evaluation {ATTITUDE_SCORES} scores attitudes and torques, but plant {plant} "
            "has no quaternion attitude (use it with plant "
            f"{' or '.join(sorted(QUATERNION_PLANTS))})"
        )
    frame = _state_frame(ctx) if sec.frame == "state" else sec.frame
    signal = {"inertial": "quaternion", "lvlh": "attitude_lvlh"}.get(frame)
    if signal is None:
        raise ValueError(f"evaluations.frame = {sec.frame!r}: one of 'inertial', 'lvlh', 'state'")
    if not any(s.name == signal for s in ctx.plant.signals()):
        raise CompositionError(
            f"evaluation {ATTITUDE_SCORES} with frame {frame} reads the plant's {signal}, but "
            f"plant {plant} records none"
        )
    q = _quaternions(sec.desired_quaternion, ctx.count, "evaluations.desired_quaternion")
    return AttitudeScores(desired_quaternion=as_float(q), attitude_signal=signal)


register_component_type(
    "evaluation",
    ATTITUDE_SCORES,
    AttitudeScoresSection,
    _attitude_scores,
    "attitude error against a common attitude, pairwise synchronisation error, applied torque",
)
