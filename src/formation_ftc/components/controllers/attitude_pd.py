"""Controller ``attitude-pd``: the quaternion PD attitude law, the non-fault-tolerant attitude baseline,
towards a fixed desired attitude in the plant's state frame.

Reads only :class:`~formation_ftc.sim.components.FlightInputs`: the measured attitude state
``{"omega": (N, 3), "q": (N, 4)}`` of a quaternion plant (body rate [rad/s] and body -> reference
quaternion, vector first, in the plant's ``state_frame``) -- the plant state itself, measured without
``[sensors]`` (the capabilities ``quaternion-attitude-state`` and ``plant-state-measurement``). No
communication, no fault estimate, no adaptation; any torque limit is the actuator's.
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np
from pydantic import Field

from formation_ftc.components._registry import BuildContext, per_spacecraft, register
from formation_ftc.components._sections import UnitQuaternions, quaternion_rows
from formation_ftc.config.base import StrictModel
from formation_ftc.core.quaternion import quat_conjugate, quat_multiply
from formation_ftc.sim.components import Controller, FlightInputs, Signal, component, static
from formation_ftc.sim.contract import as_float

__all__ = ["AttitudePdController", "AttitudePdSection", "error_quaternion", "QUATERNION_LAW_NEEDS"]

#: what a quaternion attitude law reading the raw plant state needs from the loop
QUATERNION_LAW_NEEDS = {
    "quaternion-attitude-state": "hold its attitude (it reads the body rate and quaternion)",
    "plant-state-measurement": "read the plant's body rate and quaternion unchanged",
}


def error_quaternion(q, q_desired):
    """Attitude error ``q_e = q_d^* (x) q`` (body -> desired frame), vector first, shape (..., 4) [-].

    ``q`` and ``q_desired`` are body -> reference and desired -> reference quaternions.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Body -> reference quaternion(s), vector first [-].
    q_desired : array_like, shape (..., 4)
        Desired -> reference quaternion(s), vector first [-].

    Returns
    -------
    jax.Array, shape (..., 4)
        The error quaternion q_e [-].

    Examples
    --------
    A body turned 90 deg about z from a desired attitude turned 30 deg about z: a 60 deg error about z.

    >>> import numpy as np
    >>> from formation_ftc.components.controllers.attitude_pd import error_quaternion
    >>> def about_z(deg):
    ...     h = np.radians(deg) / 2
    ...     return np.array([0.0, 0.0, np.sin(h), np.cos(h)])
    >>> qe = np.asarray(error_quaternion(about_z(90.0), about_z(30.0)))
    >>> bool(np.allclose(qe, about_z(60.0)))
    True
    """
    return quat_multiply(quat_conjugate(q_desired), q)


@component
class AttitudePdController(Controller):
    """Quaternion PD law towards a fixed desired attitude [N m, body axes]::

        q_e = q_d^* (x) q_i                                              (1)
        tau_i = -K_p sign(q_e4) q_e,v - K_d (omega_i - omega_d)          (2)

    ``q_i`` is the measured body -> reference quaternion and ``omega_i`` the measured body rate relative
    to the reference frame (body axes) -- the plant's ``state_frame``: inertial, or LVLH (then the law
    holds LVLH pointing). The desired attitude ``q_d`` is fixed in that frame, so ``omega_d = 0``.
    ``sign(q_e4)`` (with sign(0) = +1) takes the shorter of the two rotations (no unwinding).

    Leaves: ``K_p`` () or (N,) [N m] (per unit quaternion vector; the small-angle stiffness is K_p / 2
    [N m / rad]); ``K_d`` () or (N,) [N m s]; ``desired_quaternion`` (N, 4) [-], unit, vector first.
    Records ``attitude_error_quaternion`` (N, 4) [-], the error (1).
    """

    quantity = "torque"

    count: int = static()
    K_p: Any = 1.0  # [N m]
    K_d: Any = 1.0  # [N m s]
    desired_quaternion: Any = None  # (N, 4) [-]

    def _desired(self):
        if self.desired_quaternion is None:
            return jnp.broadcast_to(jnp.array([0.0, 0.0, 0.0, 1.0]), (self.count, 4))
        return jnp.asarray(self.desired_quaternion)

    def output(self, t, state, inputs: FlightInputs):
        w, q = inputs.measurement["omega"], inputs.measurement["q"]
        qe = error_quaternion(q, self._desired())  # (1)
        sign = jnp.where(qe[:, 3:4] < 0.0, -1.0, 1.0)
        kp = jnp.broadcast_to(jnp.asarray(self.K_p, dtype=jnp.float64), (self.count,))[:, None]
        kd = jnp.broadcast_to(jnp.asarray(self.K_d, dtype=jnp.float64), (self.count,))[:, None]
        tau = -kp * sign * qe[:, 0:3] - kd * w  # (2), omega_d = 0 in the reference frame
        return tau, None, {"attitude_error_quaternion": qe}

    def signals(self):
        dims = ("spacecraft", "quaternion_component")
        q_e = "attitude error quaternion q_d^* (x) q (vector part first)"
        return (Signal("attitude_error_quaternion", dims, "1", q_e, "body"),)

    def needs(self) -> dict[str, str]:
        return dict(QUATERNION_LAW_NEEDS)


class AttitudePdSection(StrictModel):
    """tau = -K_p sign(q_e4) q_e,v - K_d omega, q_e = q_d^* (x) q, in the plant's state frame."""

    K_p: float | list[float] = Field(
        description="Attitude gain K_p [N m] per unit error-quaternion vector (small-"
        "angle stiffness K_p / 2 [N m/rad]), one or per spacecraft, > 0."
    )
    K_d: float | list[float] = Field(
        description="Rate gain K_d [N m s], one or per spacecraft, > 0."
    )
    desired_quaternion: UnitQuaternions = Field(
        None,
        description="Desired attitude, body -> state frame, one unit quaternion [q1, q2, q3, q4] (vector "
        "first) or one per spacecraft [-] (default identity: aligned with the state frame).",
    )


def _build(sec: AttitudePdSection, ctx: BuildContext) -> AttitudePdController:
    """The controller of a validated ``[controller] type = "attitude-pd"`` section."""
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
            quaternion_rows(sec.desired_quaternion, n, "controller.desired_quaternion")
        ),
    )


register(
    "controller",
    "attitude-pd",
    AttitudePdSection,
    _build,
    "quaternion PD attitude baseline towards a fixed attitude in the plant's state frame, "
    "no fault tolerance",
)
