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

from formation_ftc.components.expressions import vector_expression
from formation_ftc.components.plants.quaternion_rigid_body import QUATERNION_COMPONENTS
from formation_ftc.core.dynamics.gravity_gradient import (
    attitude_relative_to_lvlh,
    gravity_gradient_torque_unit,
    orbit_normal_in_body,
    radial_unit_in_body,
)
from formation_ftc.core.quaternion import quat_kinematics
from formation_ftc.core.vector3 import norm3
from formation_ftc.sim.components import Plant, Signal, TruthInputs, component, static

__all__ = ["AttitudeTruthPlant", "batched_inverse_3x3"]

VEC = ("spacecraft", "axis")


def batched_inverse_3x3(J):
    """Inverse of every (..., 3, 3) matrix by its adjugate (plain arithmetic that XLA fuses)."""
    a, b, c = J[..., 0, :], J[..., 1, :], J[..., 2, :]
    cols = jnp.stack([jnp.cross(b, c), jnp.cross(c, a), jnp.cross(a, b)], axis=-1)
    det = jnp.sum(a * jnp.cross(b, c), axis=-1)
    return cols / det[..., None, None]


@component
class AttitudeTruthPlant(Plant):
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

    State ``{"omega": (N, 3), "q": (N, 4)}``. Records the inertial attitude and rate (the signals of the
    quaternion rigid-body plant), the attitude relative to LVLH ``attitude_lvlh`` (body -> LVLH
    quaternion), the body rate relative to LVLH ``angular_velocity_lvlh`` (omega - n o_b, body axes), the
    gravity-gradient torque and the usage integral ``torque_impulse`` = int |tau_cmd| dt [N m s] of the
    commanded torque.
    """

    quantity = "torque"

    inertia: Any  # (N, 3, 3) [kg m^2]
    initial_omega: Any  # (N, 3) [rad/s]
    initial_quaternion: Any  # (N, 4) [-], vector first, body -> inertial
    semi_major_axis: Any  # () circular orbit radius [m]
    mu: Any  # () [m^3/s^2]
    initial_argument_of_latitude: Any  # () [rad]
    disturbance_torque: tuple[str, str, str] = static(default=("0", "0", "0"))  # iota(t) [N m]
    gravity_gradient: bool = static(default=True)

    @property
    def count(self) -> int:
        return int(jnp.shape(self.initial_omega)[0])

    def initial_state(self):
        return {"omega": self.initial_omega, "q": self.initial_quaternion}

    def exogenous(self, t):
        return {"iota": vector_expression(self.disturbance_torque, "disturbance.torque", t, self.count)}

    def orbit_rate(self):
        """n = sqrt(mu / a^3) [rad/s]."""
        return jnp.sqrt(self.mu / self.semi_major_axis**3)

    def argument_of_latitude(self, t):
        """u(t) = u0 + n t [rad]."""
        return self.initial_argument_of_latitude + self.orbit_rate() * t

    def gravity_gradient_torque(self, t, q):
        """tau_gg (N, 3) [N m, body axes] at time t [s] for the attitudes q (N, 4)."""
        r_b = radial_unit_in_body(q, self.argument_of_latitude(t))
        return gravity_gradient_torque_unit(r_b, self.inertia, self.mu / self.semi_major_axis**3)

    def rates(self, t, x, torque):
        """``{"omega": omega', "q": q'}`` under the external torque ``torque`` (N, 3) [N m] plus gravity
        gradient (when on)."""
        omega, q = x["omega"], x["q"]
        J = self.inertia
        total = -jnp.cross(omega, jnp.einsum("nij,nj->ni", J, omega)) + torque
        if self.gravity_gradient:
            total = total + self.gravity_gradient_torque(t, q)
        omega_dot = jnp.einsum("nij,nj->ni", batched_inverse_3x3(J), total)  # J w' = -w x J w + tau_gg + tau + iota
        return {"omega": omega_dot, "q": quat_kinematics(q, omega)}

    def derivative(self, t, x, inputs: TruthInputs):
        return self.rates(t, x, inputs.force + inputs.exogenous["iota"])

    def usage_names(self):
        return ("torque_impulse",)

    def usage_rates(self, t, x, command):
        return {"torque_impulse": norm3(command)}

    def signals(self):
        return (Signal("angular_velocity", VEC, "rad s-1", "body angular velocity relative to the inertial frame",
                       "body"),
                Signal("quaternion", ("spacecraft", "quaternion_component"), "1",
                       "attitude quaternion body -> inertial (vector part first)", "body"),
                Signal("attitude_lvlh", ("spacecraft", "quaternion_component"), "1",
                       "attitude quaternion body -> LVLH (vector part first)", "body"),
                Signal("angular_velocity_lvlh", VEC, "rad s-1", "body angular velocity relative to LVLH", "body"),
                Signal("gravity_gradient_torque", VEC, "N m", "gravity-gradient torque", "body"),
                Signal("torque_impulse", ("spacecraft",), "N m s", "integral of the commanded torque norm"))

    def coords(self):
        return {"quaternion_component": QUATERNION_COMPONENTS}

    def outputs(self, t, x, inputs):
        omega, q = x["omega"], x["q"]
        u = self.argument_of_latitude(t)
        gg = self.gravity_gradient_torque(t, q) if self.gravity_gradient else jnp.zeros_like(omega)
        return {"angular_velocity": omega, "quaternion": q,
                "attitude_lvlh": attitude_relative_to_lvlh(q, u),
                "angular_velocity_lvlh": omega - self.orbit_rate() * orbit_normal_in_body(q),
                "gravity_gradient_torque": gg}
