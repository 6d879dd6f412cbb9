"""Plant ``attitude-truth``: quaternion rigid bodies on a circular orbit with the gravity-gradient
torque.

Frames and conventions are those of :mod:`formation_ftc.core.dynamics.gravity_gradient`: the attitude
quaternion ``q = [q_v, q4]`` (vector first) maps body to *inertial* components, the orbit is circular
in the inertial x-y plane, LVLH is x radial / y along-track / z orbit normal. The state layout and the
quaternion convention are those of
:class:`~formation_ftc.components.plants.quaternion_rigid_body.QuaternionRigidBodyPlant` (the capability
``quaternion-attitude-state``), so the same sensors (``quaternion-euler``), allocations
(``euler-torque-allocation``), FDIs and attitude laws drive either plant. ``state_frame = "lvlh"`` puts
the attitude and body rate relative to LVLH in the state, so those components -- and a law's desired
attitude -- then work relative to LVLH (LVLH pointing). The plant also records the attitude relative
to LVLH (the capability ``lvlh-attitude``).
"""

from __future__ import annotations

import math
from typing import Any, Literal

import jax.numpy as jnp
import numpy as np
from pydantic import Field, model_validator

from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.components._sections import Inertia, Vec3, expression_text, section_floats
from formation_ftc.components.plants._rigid_body import (
    RigidBodyAttitudeSection,
    RigidBodyTorquePlant,
)
from formation_ftc.core.constants import MU_EARTH, R_EARTH
from formation_ftc.core.dynamics.attitude_quaternion import inverse_3x3
from formation_ftc.core.dynamics.gravity_gradient import (
    attitude_relative_to_lvlh,
    gravity_gradient_torque_unit,
    orbit_normal_in_body,
    quaternion_lvlh_to_inertial,
    radial_unit_in_body,
)
from formation_ftc.core.quaternion import quat_kinematics, quat_multiply, rotation_matrix
from formation_ftc.core.vector3 import norm3
from formation_ftc.sim.components import CompositionError, Signal, TruthInputs, component, static
from formation_ftc.sim.contract import VEC, as_float

__all__ = [
    "AttitudeTruthPlant",
    "AttitudeTruthSection",
    "initial_state_in",
    "initial_inertial_state",
    "STATE_FRAMES",
]

#: frames the plant can integrate the attitude in
STATE_FRAMES = ("inertial", "lvlh")


@component
class AttitudeTruthPlant(RigidBodyTorquePlant):
    """N rigid bodies with inertial attitude and body rate, on a circular orbit, with gravity gradient::

        J_i omega_i' = -omega_i x J_i omega_i + tau_gg,i + tau_i + iota_i(t)
        q_v' = 1/2 (q4 omega - omega x q_v),  q4' = -1/2 omega^T q_v
        tau_gg,i = 3 mu / a^3  r_b x (J_i r_b),  r_b = C(q_i)^T [cos u, sin u, 0],  u = u0 + n t

    omega_i [rad/s]: body angular velocity relative to the inertial frame, in body axes; q_i: body ->
    inertial quaternion (vector first); J_i [kg m^2]: inertia of spacecraft i, (N, 3, 3); tau_i [N m]:
    applied torque (after the actuator chain), body axes; iota_i(t) [N m]: disturbance torque
    (expressions in t [s] and the 1-based spacecraft number i, body axes); a [m]: orbit radius (the
    semi-major axis of the circular orbit); mu [m^3/s^2]; n = sqrt(mu / a^3) [rad/s]; u0 [rad]: argument
    of latitude at t = 0. ``gravity_gradient = False`` drops tau_gg (then a, u0 only set the LVLH frame
    of the outputs). Every spacecraft flies the same orbit (the formation's separations are negligible
    against a for the torque).

    State ``{"omega": (N, 3), "q": (N, 4)}`` in ``state_frame``:

    * ``"inertial"``: omega_i and q_i above;
    * ``"lvlh"``: the body rate relative to LVLH ``w_r = omega - n o_b`` (body axes, o_b the orbit
      normal in body axes = third row of C(q_L)) and the body -> LVLH quaternion q_L, integrated as::

          w_r' = omega' + n w_r x o_b,   q_L' = 1/2 q_L (x) [w_r, 0],   r_b = first row of C(q_L)

      (o_b is fixed in LVLH, so its body-axes rate is o_b x w_r). Sensors, allocations and laws that
      read the state then work relative to LVLH: an attitude law holds LVLH pointing.

    Records in both cases the inertial attitude and rate (``quaternion``, ``angular_velocity``: the
    signals of the quaternion rigid-body plant), the attitude relative to LVLH ``attitude_lvlh`` (body ->
    LVLH quaternion, ``C(q_L) = Rz(u)^T C(q)``), the body rate relative to LVLH
    ``angular_velocity_lvlh``, the gravity-gradient torque and the usage integral ``torque_impulse`` =
    int |tau_cmd| dt [N m s] of the commanded torque.
    """

    inertia: Any  # (N, 3, 3) [kg m^2]
    initial_body_rate: Any  # (N, 3) [rad/s], relative to state_frame
    initial_quaternion: Any  # (N, 4) [-], vector first, body -> state_frame
    semi_major_axis: Any  # () circular orbit radius [m]
    mu: Any  # () [m^3/s^2]
    initial_argument_of_latitude: Any  # () [rad]
    disturbance_torque: tuple[str, str, str] = static(default=("0", "0", "0"))  # iota(t) [N m]
    gravity_gradient: bool = static(default=True)
    state_frame: str = static(default="inertial")  # "inertial" or "lvlh"

    def __post_init__(self):
        if self.state_frame not in STATE_FRAMES:
            raise CompositionError(
                f"AttitudeTruthPlant.state_frame = {self.state_frame!r}: one of {STATE_FRAMES}"
            )

    def provides(self) -> frozenset[str]:
        return super().provides() | {"lvlh-attitude"}

    def orbit_rate(self):
        """n = sqrt(mu / a^3) [rad/s]."""
        return jnp.sqrt(self.mu / self.semi_major_axis**3)

    def argument_of_latitude(self, t):
        """u(t) = u0 + n t [rad]."""
        return self.initial_argument_of_latitude + self.orbit_rate() * t

    def _lvlh(self) -> bool:
        return self.state_frame == "lvlh"

    def gravity_gradient_torque(self, t, q):
        """tau_gg (N, 3) [N m, body axes] at time t [s] for the attitudes q (N, 4) of ``state_frame``."""
        r_b = (
            rotation_matrix(q)[..., 0, :]
            if self._lvlh()
            else radial_unit_in_body(q, self.argument_of_latitude(t))
        )
        return gravity_gradient_torque_unit(r_b, self.inertia, self.mu / self.semi_major_axis**3)

    def rates(self, t, x, torque):
        """``{"omega": ..., "q": ...}`` rates of the state (``state_frame``) under the external torque
        ``torque`` (N, 3) [N m] plus gravity gradient (when on)."""
        w, q = x["omega"], x["q"]
        J = self.inertia
        if self._lvlh():
            n = self.orbit_rate()
            o_b = orbit_normal_in_body(q)
            omega = w + n * o_b  # inertial body rate
        else:
            omega = w
        total = -jnp.cross(omega, jnp.einsum("nij,nj->ni", J, omega)) + torque
        if self.gravity_gradient:
            total = total + self.gravity_gradient_torque(t, q)
        # J w' = -w x J w + tau_gg + tau + iota
        omega_dot = jnp.einsum("nij,nj->ni", inverse_3x3(J), total)
        if self._lvlh():  # w_r' = w' + n w_r x o_b
            return {"omega": omega_dot + n * jnp.cross(w, o_b), "q": quat_kinematics(q, w)}
        return {"omega": omega_dot, "q": quat_kinematics(q, omega)}

    def inertial_and_lvlh(self, t, x):
        """``(omega, q, w_r, q_L)``: the inertial body rate [rad/s] and attitude, and the body rate
        relative to LVLH [rad/s] and body -> LVLH attitude, from the state at time ``t`` [s]."""
        w, q = x["omega"], x["q"]
        u = self.argument_of_latitude(t)
        n = self.orbit_rate()
        o_b = orbit_normal_in_body(q)
        if self._lvlh():
            q_il = jnp.broadcast_to(quaternion_lvlh_to_inertial(u), q.shape)
            return w + n * o_b, quat_multiply(q_il, q), w, q
        return w, q, w - n * o_b, attitude_relative_to_lvlh(q, u)

    def derivative(self, t, x, inputs: TruthInputs):
        return self.rates(t, x, inputs.force + inputs.exogenous["iota"])

    def usage_names(self):
        return ("torque_impulse",)

    def usage_rates(self, t, x, command):
        return {"torque_impulse": norm3(command)}

    def signals(self):
        return (
            Signal(
                "angular_velocity",
                VEC,
                "rad s-1",
                "body angular velocity relative to the inertial frame",
                "body",
            ),
            Signal(
                "quaternion",
                ("spacecraft", "quaternion_component"),
                "1",
                "attitude quaternion body -> inertial (vector part first)",
                "body",
            ),
            Signal(
                "attitude_lvlh",
                ("spacecraft", "quaternion_component"),
                "1",
                "attitude quaternion body -> LVLH (vector part first)",
                "body",
            ),
            Signal(
                "angular_velocity_lvlh",
                VEC,
                "rad s-1",
                "body angular velocity relative to LVLH",
                "body",
            ),
            Signal("gravity_gradient_torque", VEC, "N m", "gravity-gradient torque", "body"),
            Signal(
                "torque_impulse", ("spacecraft",), "N m s", "integral of the commanded torque norm"
            ),
        )

    def outputs(self, t, x, inputs):
        omega, q, w_r, q_l = self.inertial_and_lvlh(t, x)
        gg = (
            self.gravity_gradient_torque(t, x["q"])
            if self.gravity_gradient
            else jnp.zeros_like(omega)
        )
        return {
            "angular_velocity": omega,
            "quaternion": q,
            "attitude_lvlh": q_l,
            "angular_velocity_lvlh": w_r,
            "gravity_gradient_torque": gg,
        }


Mat3 = tuple[Vec3, Vec3, Vec3]


class AttitudeTruthSection(RigidBodyAttitudeSection):
    """Rigid bodies on a circular orbit with the gravity-gradient torque (inertial attitude)."""

    inertia: Inertia = Field(
        description="Principal inertia diag(J) [kg m^2], each > 0: the truth of every spacecraft "
        "unless inertia_matrices is given (an attitude law's model is stated in its own section)."
    )
    inertia_matrices: list[Mat3] | None = builder_input(
        None,
        description="Full inertia matrix per spacecraft (one 3x3 row list each, or a single one for all) "
        "[kg m^2]: symmetric, positive definite, satisfying the triangle inequalities; "
        "overrides `inertia` in the truth.",
    )
    semi_major_axis: float = Field(
        7.0e6,
        ge=R_EARTH,
        le=1.0e9,
        description="Radius of the circular orbit [m] (>= the Earth's equatorial radius).",
    )
    mu: float = Field(MU_EARTH, gt=0.0, description="Gravitational parameter [m^3/s^2].")
    initial_argument_of_latitude_deg: float = builder_input(
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
    initial_frame: Literal["inertial", "lvlh"] = builder_input(
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
        given = self.inertia_matrices
        mats = (
            np.diag(np.asarray(self.inertia, float)) if given is None else np.asarray(given, float)
        )
        return np.broadcast_to(mats, (self.count, 3, 3)).copy()


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
    """The initial state relative to ``frame`` from the section's initial attitude and rate given in
    ``initial_frame``.

    LVLH -> inertial: ``q = q_z(u0) (x) q_L``, ``omega = w_r + n o_b``; inertial -> LVLH:
    ``q_L = q_z(u0)^* (x) q``, ``w_r = omega - n o_b``, with o_b the orbit normal in body axes (the
    orbit normal is the z axis of both frames).

    Parameters
    ----------
    sec : AttitudeTruthSection
        A validated section.
    frame : {"inertial", "lvlh"}
        The frame of the result.

    Returns
    -------
    tuple of numpy.ndarray
        ``(omega (N, 3) [rad/s], q (N, 4) [-])`` at t = 0 relative to ``frame``.

    Examples
    --------
    Aligned with LVLH at u0 = 90 deg: turned 90 deg about the orbit normal from the inertial frame.

    >>> sec = AttitudeTruthSection(inertia=(10.0, 20.0, 25.0), initial_quaternion=[(0, 0, 0, 1)],
    ...                            initial_frame="lvlh", initial_argument_of_latitude_deg=90.0)
    >>> w, q = initial_state_in(sec, "inertial")
    >>> np.round(q, 6).tolist()
    [[0.0, 0.0, 0.707107, 0.707107]]
    """
    q = sec.given_quaternions()
    w = sec.body_rates()
    if sec.initial_frame == frame:
        return w, q
    u0 = math.radians(sec.initial_argument_of_latitude_deg)
    sign = 1.0 if frame == "inertial" else -1.0  # lvlh -> inertial, or back
    u = sign * u0
    rz = np.array([0.0, 0.0, math.sin(0.5 * u), math.cos(0.5 * u)])  # q_z(u)
    q_new = _quat_mul(np.broadcast_to(rz, q.shape), q)
    w_new = w + sign * sec.orbit_rate() * _orbit_normal_in_body(q)
    return w_new, q_new


def initial_inertial_state(sec: AttitudeTruthSection) -> tuple[np.ndarray, np.ndarray]:
    """``(omega (N, 3) [rad/s], q (N, 4))`` at t = 0 relative to the inertial frame
    (:func:`initial_state_in`).

    Parameters
    ----------
    sec : AttitudeTruthSection
        A validated section.

    Returns
    -------
    tuple of numpy.ndarray
        Inertial body rates and body -> inertial quaternions.

    Examples
    --------
    >>> sec = AttitudeTruthSection(inertia=(10.0, 20.0, 25.0), initial_quaternion=[(0, 0, 0, 1)])
    >>> [x.tolist() for x in initial_inertial_state(sec)]
    [[[0.0, 0.0, 0.0]], [[0.0, 0.0, 0.0, 1.0]]]
    """
    return initial_state_in(sec, "inertial")


def _build(sec: AttitudeTruthSection, ctx: BuildContext) -> AttitudeTruthPlant:
    """The plant of a validated ``[plant] type = "attitude-truth"`` section."""
    w0, q0 = initial_state_in(sec, sec.state_frame)
    return AttitudeTruthPlant(
        inertia=as_float(sec.inertia_tensor()),
        initial_body_rate=as_float(w0),
        initial_quaternion=as_float(q0),
        **section_floats(sec, "semi_major_axis", "mu"),
        initial_argument_of_latitude=as_float(math.radians(sec.initial_argument_of_latitude_deg)),
        disturbance_torque=expression_text(sec.disturbance_torque),
        gravity_gradient=sec.gravity_gradient,
        state_frame=sec.state_frame,
    )


register(
    "plant",
    "attitude-truth",
    AttitudeTruthSection,
    _build,
    "rigid-body attitudes (inertial quaternion) on a circular orbit with the gravity-gradient "
    "torque, driven by body torques",
)
