"""Plant ``quaternion-rigid-body``: rigid-body attitude of every spacecraft with quaternion kinematics
(Yang2013 eqs. (4), (5)), driven by body torques.

State ``{"omega": (N, 3), "q": (N, 4)}`` (body rate and quaternion, vector part first: the capability
``quaternion-attitude-state``), one principal inertia for every spacecraft.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pydantic import Field

from formation_ftc.components._registry import BuildContext, register
from formation_ftc.components._sections import expression_text
from formation_ftc.components.plants._rigid_body import (
    QUATERNION_COMPONENTS,
    RigidBodyAttitudeSection,
    RigidBodyTorquePlant,
)
from formation_ftc.core.dynamics.attitude_quaternion import rigid_body_quaternion_rates
from formation_ftc.sim.components import Signal, TruthInputs, component, static
from formation_ftc.sim.contract import VEC, as_float

__all__ = ["QuaternionRigidBodyPlant", "QuaternionPlantSection", "QUATERNION_COMPONENTS"]


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
    initial_body_rate: Any  # (N, 3) [rad/s]
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
                VEC,
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


class QuaternionPlantSection(RigidBodyAttitudeSection):
    """N rigid bodies with quaternion kinematics (one principal inertia for every spacecraft)."""

    gyroscopic: bool = Field(
        True, description="Include -omega x J omega (false: the error-level form)."
    )


def _build(sec: QuaternionPlantSection, ctx: BuildContext) -> QuaternionRigidBodyPlant:
    """The plant of a validated ``[plant] type = "quaternion-rigid-body"`` section."""
    return QuaternionRigidBodyPlant(
        inertia=as_float(np.diag(sec.inertia)),
        initial_body_rate=as_float(sec.body_rates()),
        initial_quaternion=as_float(sec.quaternions()),
        disturbance_torque=expression_text(sec.disturbance_torque),
        gyroscopic=sec.gyroscopic,
    )


register(
    "plant",
    "quaternion-rigid-body",
    QuaternionPlantSection,
    _build,
    "rigid-body attitudes with quaternion kinematics, driven by body torques (Yang2013 (4))",
)
