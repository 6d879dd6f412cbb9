"""Attitude truth: quaternion rigid bodies on a circular orbit with the gravity-gradient torque.

Frames and conventions are those of :mod:`formation_ftc.core.dynamics.gravity_gradient`: the attitude
quaternion ``q = [q_v, q4]`` (vector first) maps body to *inertial* components, the orbit is circular
in the inertial x-y plane, LVLH is x radial / y along-track / z orbit normal. The state layout and the
quaternion convention are those of
:class:`~formation_ftc.components.plants.quaternion_rigid_body.QuaternionRigidBodyPlant`, so the same
sensors, actuators and attitude laws drive either plant.
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp

from formation_ftc.components.plants.quaternion_rigid_body import (
    RigidBodyTorquePlant,
)
from formation_ftc.core.dynamics.gravity_gradient import (
    attitude_relative_to_lvlh,
    gravity_gradient_torque_unit,
    orbit_normal_in_body,
    quaternion_lvlh_to_inertial,
    radial_unit_in_body,
)
from formation_ftc.core.quaternion import quat_kinematics, quat_multiply, rotation_matrix
from formation_ftc.core.vector3 import norm3
from formation_ftc.sim.components import (
    CompositionError,
    Signal,
    TruthInputs,
    component,
    static,
)

__all__ = ["AttitudeTruthPlant", "batched_inverse_3x3", "STATE_FRAMES"]

#: frames the plant can integrate the attitude in
STATE_FRAMES = ("inertial", "lvlh")

VEC = ("spacecraft", "axis")


def batched_inverse_3x3(J):
    """Inverse of every (..., 3, 3) matrix by its adjugate (plain arithmetic that XLA fuses).

    Parameters
    ----------
    J : array_like, shape (..., 3, 3)
        Invertible matrices, e.g. inertias [kg m^2].

    Returns
    -------
    jax.Array, shape (..., 3, 3)
        The inverses (e.g. [1/(kg m^2)]).

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.plants.attitude_truth import batched_inverse_3x3
    >>> J = np.array([np.diag([10.0, 20.0, 40.0]), [[2.0, 1.0, 0.0], [1.0, 2.0, 0.0], [0.0, 0.0, 1.0]]])
    >>> bool(np.allclose(batched_inverse_3x3(J), np.linalg.inv(J)))
    True
    >>> np.asarray(batched_inverse_3x3(J))[0].diagonal()
    array([0.1  , 0.05 , 0.025])
    """
    a, b, c = J[..., 0, :], J[..., 1, :], J[..., 2, :]
    cols = jnp.stack([jnp.cross(b, c), jnp.cross(c, a), jnp.cross(a, b)], axis=-1)
    det = jnp.sum(a * jnp.cross(b, c), axis=-1)
    return cols / det[..., None, None]


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
    initial_omega: Any  # (N, 3) [rad/s], relative to state_frame
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
        omega_dot = jnp.einsum(
            "nij,nj->ni", batched_inverse_3x3(J), total
        )  # J w' = -w x J w + tau_gg + tau + iota
        if self._lvlh():
            return {
                "omega": omega_dot + n * jnp.cross(w, o_b),
                "q": quat_kinematics(q, w),
            }  # w_r' = w' + n w_r x o_b
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
