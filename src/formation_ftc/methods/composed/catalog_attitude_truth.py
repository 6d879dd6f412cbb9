"""Catalog: the attitude truth plant (``plant.type = "attitude-truth"``) for composed scenarios.

Quaternion rigid bodies with inertial attitude on a circular orbit with the gravity-gradient torque
(:class:`~formation_ftc.components.plants.attitude_truth.AttitudeTruthPlant`). It has the state layout
of ``quaternion-rigid-body``, so the Euler sensors (``quaternion-euler``), the generalised-torque
allocation (``euler-torque-allocation``), the scripted FDI and the Euler-angle attitude law
(``networked-el-hinf``) compose with it exactly as with that plant. ``state_frame = "lvlh"`` puts the
attitude and body rate relative to LVLH in the state, so those components -- and the law's desired
attitude -- then work relative to LVLH (LVLH pointing).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Literal

import numpy as np
from pydantic import Field, model_validator

from formation_ftc.core.constants import MU_EARTH
from formation_ftc.methods.composed import BuildContext, register_component_type
from formation_ftc.methods.composed.catalog_attitude import (
    QUATERNION_PLANTS,
    RigidBodyAttitudeSection,
)
from formation_ftc.sim.contract import as_float

if TYPE_CHECKING:
    from formation_ftc.components.plants.attitude_truth import AttitudeTruthPlant

__all__ = [
    "ATTITUDE_TRUTH_PLANT",
    "AttitudeTruthSection",
    "initial_inertial_state",
    "initial_state_in",
]

ATTITUDE_TRUTH_PLANT = "attitude-truth"
EARTH_RADIUS = 6_378_137.0  # equatorial radius [m] (WGS 84), lower bound of the orbit radius

Vec3 = tuple[float, float, float]
Mat3 = tuple[Vec3, Vec3, Vec3]


class AttitudeTruthSection(RigidBodyAttitudeSection):
    """Rigid bodies on a circular orbit with the gravity-gradient torque (inertial attitude)."""

    inertia: Vec3 = Field(
        description="Principal inertia diag(J) [kg m^2], each > 0: the truth of every "
        "spacecraft unless inertia_matrices is given (an attitude law's model is "
        "stated in its own section)."
    )
    inertia_matrices: list[Mat3] | None = Field(
        None,
        description="Full inertia matrix per spacecraft (one 3x3 row list each, or a single one for all) "
        "[kg m^2]: symmetric, positive definite, satisfying the triangle inequalities; "
        "overrides `inertia` in the truth.",
    )
    semi_major_axis: float = Field(
        7.0e6,
        ge=EARTH_RADIUS,
        le=1.0e9,
        description="Radius of the circular orbit [m] (>= the Earth's equatorial radius).",
    )
    mu: float = Field(MU_EARTH, gt=0.0, description="Gravitational parameter [m^3/s^2].")
    initial_argument_of_latitude_deg: float = Field(
        0.0,
        ge=-360.0,
        le=360.0,
        description="Argument of latitude u0 of the spacecraft at t = 0 [deg].",
    )
    gravity_gradient: bool = Field(True, description="Apply the gravity-gradient torque.")
    state_frame: Literal["inertial", "lvlh"] = Field(
        "inertial",
        description="Frame of the attitude the plant integrates and its sensors measure: 'inertial', or "
        "'lvlh' (attitude and body rate relative to LVLH: an attitude law then holds LVLH "
        "pointing, its desired attitude 0 being LVLH alignment).",
    )
    initial_frame: Literal["inertial", "lvlh"] = Field(
        "inertial",
        description="Frame of the initial attitude and body rate: 'inertial', or 'lvlh' (attitude "
        "relative to LVLH at t = 0, body rate relative to LVLH; converted to inertial).",
    )
    initial_body_rate: list[Vec3] | None = Field(
        None,
        description="Initial body angular velocity per spacecraft, body axes [rad/s] (default 0 in "
        "initial_frame).",
    )

    @model_validator(mode="after")
    def _check(self):
        n = self.count
        if self.inertia_matrices is not None:
            if len(self.inertia_matrices) not in (1, n):
                raise ValueError(
                    f"inertia_matrices: {len(self.inertia_matrices)} matrices for {n} spacecraft "
                    f"(give one or {n})"
                )
            for k, m in enumerate(self.inertia_matrices):
                _check_inertia(np.asarray(m, dtype=float), f"inertia_matrices[{k}]")
        return self

    def orbit_rate(self) -> float:
        """n = sqrt(mu / a^3) [rad/s]."""
        return math.sqrt(self.mu / self.semi_major_axis**3)

    def quaternions(self) -> np.ndarray:
        """(N, 4) initial body -> ``state_frame`` quaternions."""
        return initial_state_in(self, self.state_frame)[1]

    def inertia_tensor(self) -> np.ndarray:
        """(N, 3, 3) inertia of every spacecraft [kg m^2]."""
        n = self.count
        if self.inertia_matrices is None:
            return np.broadcast_to(np.diag(np.asarray(self.inertia, float)), (n, 3, 3)).copy()
        mats = np.asarray(self.inertia_matrices, dtype=float)
        return np.broadcast_to(mats, (n, 3, 3)).copy()


def _check_inertia(m: np.ndarray, field: str) -> None:
    if m.shape != (3, 3) or not np.all(np.isfinite(m)):
        raise ValueError(f"{field}: a finite 3x3 matrix is needed [kg m^2]")
    if not np.allclose(m, m.T, rtol=1e-9, atol=1e-12 * float(np.abs(m).max())):
        raise ValueError(f"{field}: not symmetric")
    eig = np.linalg.eigvalsh(m)
    if not eig[0] > 0:
        raise ValueError(
            f"{field}: not positive definite (smallest principal inertia {eig[0]:.6g} kg m^2)"
        )
    if eig[0] + eig[1] < eig[2] * (1.0 - 1e-12):
        raise ValueError(
            f"{field}: principal inertias {eig[0]:.6g}, {eig[1]:.6g}, {eig[2]:.6g} kg m^2 violate "
            "the triangle inequality J1 + J2 >= J3 of a rigid body"
        )


def _rz_quaternion(u: float) -> np.ndarray:
    return np.array([0.0, 0.0, math.sin(0.5 * u), math.cos(0.5 * u)])


def _quat_mul(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    pv, p4 = p[..., :3], p[..., 3:]
    qv, q4 = q[..., :3], q[..., 3:]
    return np.concatenate(
        [p4 * qv + q4 * pv + np.cross(pv, qv), p4 * q4 - np.sum(pv * qv, -1, keepdims=True)], -1
    )


def _orbit_normal_in_body(q: np.ndarray) -> np.ndarray:
    """Third row of C(q) (the reference frame's z axis in body axes), (N, 3)."""
    qv, q4 = q[:, :3], q[:, 3]
    return np.stack(
        [
            2 * (qv[:, 0] * qv[:, 2] - q4 * qv[:, 1]),
            2 * (qv[:, 1] * qv[:, 2] + q4 * qv[:, 0]),
            q4**2 - qv[:, 0] ** 2 - qv[:, 1] ** 2 + qv[:, 2] ** 2,
        ],
        axis=-1,
    )


def initial_state_in(sec: AttitudeTruthSection, frame: str) -> tuple[np.ndarray, np.ndarray]:
    """(omega (N, 3) [rad/s], q (N, 4)) at t = 0 relative to ``frame`` ("inertial" or "lvlh") from the
    section's initial attitude and rate given in ``initial_frame``.

    LVLH -> inertial: ``q = q_z(u0) (x) q_L``, ``omega = w_r + n o_b``; inertial -> LVLH:
    ``q_L = q_z(u0)^* (x) q``, ``w_r = omega - n o_b``, with o_b the orbit normal in body axes (the
    orbit normal is the z axis of both frames).
    """
    n_sc = sec.count
    q = sec.given_quaternions()
    w = (
        np.zeros((n_sc, 3))
        if sec.initial_body_rate is None
        else np.asarray(sec.initial_body_rate, float)
    )
    if sec.initial_frame == frame:
        return w, q
    u0 = math.radians(sec.initial_argument_of_latitude_deg)
    sign = 1.0 if frame == "inertial" else -1.0  # lvlh -> inertial, or back
    q_new = _quat_mul(np.broadcast_to(_rz_quaternion(sign * u0), q.shape), q)
    w_new = w + sign * sec.orbit_rate() * _orbit_normal_in_body(q)
    return w_new, q_new


def initial_inertial_state(sec: AttitudeTruthSection) -> tuple[np.ndarray, np.ndarray]:
    """(omega (N, 3) [rad/s], q (N, 4)) at t = 0 relative to the inertial frame (:func:`initial_state_in`)."""
    return initial_state_in(sec, "inertial")


def _attitude_truth(sec: AttitudeTruthSection, ctx: BuildContext) -> AttitudeTruthPlant:
    from formation_ftc.components.plants.attitude_truth import AttitudeTruthPlant

    w0, q0 = initial_state_in(sec, sec.state_frame)
    a, b, c = sec.disturbance_torque
    return AttitudeTruthPlant(
        inertia=as_float(sec.inertia_tensor()),
        initial_omega=as_float(w0),
        initial_quaternion=as_float(q0),
        semi_major_axis=as_float(sec.semi_major_axis),
        mu=as_float(sec.mu),
        initial_argument_of_latitude=as_float(math.radians(sec.initial_argument_of_latitude_deg)),
        disturbance_torque=(str(a), str(b), str(c)),
        gravity_gradient=sec.gravity_gradient,
        state_frame=sec.state_frame,
    )


QUATERNION_PLANTS.add(ATTITUDE_TRUTH_PLANT)
register_component_type(
    "plant",
    ATTITUDE_TRUTH_PLANT,
    AttitudeTruthSection,
    _attitude_truth,
    "rigid-body attitudes (inertial quaternion) on a circular orbit with the gravity-gradient "
    "torque, driven by body torques",
)
