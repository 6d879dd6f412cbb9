"""Quaternion PD attitude law: the non-fault-tolerant attitude baseline.

Reads only :class:`~formation_ftc.sim.components.FlightInputs`: the measured attitude state
``{"omega": (N, 3), "q": (N, 4)}`` of a quaternion plant (body rate [rad/s] and body -> reference
quaternion, vector first, in the plant's ``state_frame``). No communication, no fault estimate, no
adaptation; any torque limit is the actuator's.
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp

from formation_ftc.core.quaternion import quat_conjugate, quat_multiply
from formation_ftc.sim.components import Controller, FlightInputs, Signal, component, static

__all__ = ["AttitudePdController", "error_quaternion"]


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
        return (
            Signal(
                "attitude_error_quaternion",
                ("spacecraft", "quaternion_component"),
                "1",
                "attitude error quaternion q_d^* (x) q (vector part first)",
                "body",
            ),
        )
