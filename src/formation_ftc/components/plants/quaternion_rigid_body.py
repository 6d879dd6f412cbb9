"""Rigid-body attitude of every spacecraft with quaternion kinematics (Yang2013 eqs. (4), (5))."""

from __future__ import annotations

from typing import Any

import numpy as np

from formation_ftc.components.expressions import vector_expression
from formation_ftc.core.dynamics.attitude_quaternion import rigid_body_quaternion_rates
from formation_ftc.sim.components import Plant, Signal, TruthInputs, component, static

__all__ = ["QuaternionRigidBodyPlant", "QUATERNION_COMPONENTS"]

QUATERNION_COMPONENTS = ["q1", "q2", "q3", "q4"]


class RigidBodyTorquePlant(Plant):
    """Rigid bodies in the state ``{"omega": (N, 3), "q": (N, 4)}`` from the fields ``initial_omega``,
    ``initial_quaternion``, driven by a torque plus the disturbance torque expressions
    ``disturbance_torque`` iota(t) [N m] (the state layout both quaternion attitude plants share)."""

    quantity = "torque"
    initial_omega: Any  # declared by the subclasses (dataclass fields there)

    @property
    def count(self) -> int:
        return int(np.shape(self.initial_omega)[0])

    def initial_state(self):
        return {"omega": self.initial_omega, "q": self.initial_quaternion}

    def angular_rate(self, x):
        return x["omega"]

    def exogenous(self, t):
        return {
            "iota": vector_expression(self.disturbance_torque, "disturbance.torque", t, self.count)
        }

    def coords(self):
        return {"quaternion_component": QUATERNION_COMPONENTS}


@component
class QuaternionRigidBodyPlant(RigidBodyTorquePlant):
    """N rigid bodies with body rate omega [rad/s] and attitude quaternion q = [q_v, q4] (vector first)::

        J omega' = -omega x J omega + tau + iota(t)        # Yang2013 eq. (4) (gyroscopic term optional)
        q_v' = 1/2 (q4 omega - omega x q_v),  q4' = -1/2 omega^T q_v

    with the applied torque tau [N m], the disturbance torque iota(t) [N m] (expressions in t [s] and
    the 1-based spacecraft number i) and the inertia J [kg m^2] shared by every spacecraft. State
    ``{"omega": (N, 3), "q": (N, 4)}``. ``gyroscopic = False`` drops ``-omega x J omega``: the attitude
    error dynamics (5) of Yang2013, in which that term is part of the drift Upsilon that the attitude
    law cancels (then omega, q hold the attitude error e_omega, (e_q, e_q4)).
    """

    inertia: Any  # (3, 3) [kg m^2]
    initial_omega: Any  # (N, 3) [rad/s]
    initial_quaternion: Any  # (N, 4) [-], vector first
    disturbance_torque: tuple[str, str, str] = static(default=("0", "0", "0"))  # iota(t) [N m]
    gyroscopic: bool = static(default=True)

    def rates(self, x, torque):
        """``{"omega": omega', "q": q'}`` under the total torque (control + disturbance) [N m]."""
        dw, dq = rigid_body_quaternion_rates(
            x["omega"], x["q"], torque, self.inertia, self.gyroscopic
        )
        return {"omega": dw, "q": dq}

    def derivative(self, t, x, inputs: TruthInputs):
        return self.rates(x, inputs.force + inputs.exogenous["iota"])  # Yang2013 eq. (4)

    def signals(self):
        return (
            Signal(
                "angular_velocity",
                ("spacecraft", "axis"),
                "rad s-1",
                "body angular velocity",
                "body",
            ),
            Signal(
                "quaternion",
                ("spacecraft", "quaternion_component"),
                "1",
                "attitude quaternion (vector part first)",
                "body",
            ),
        )

    def outputs(self, t, x, inputs):
        return {"angular_velocity": x["omega"], "quaternion": x["q"]}
