"""Yang2013's attitude law (13) holding a fixed attitude of a quaternion plant.

:class:`~formation_ftc.components.controllers._yang2013.Yang2013AttitudeController` reads the
error state ``(e_w, e_q, e_q4)`` of Yang2013 (7), zero at the desired attitude. This component forms that
error state from a quaternion plant's measured state and hands it to the law unchanged.
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp

from formation_ftc.components.controllers._yang2013 import Yang2013AttitudeController
from formation_ftc.components.controllers.attitude_pd import error_quaternion
from formation_ftc.sim.components import Controller, FlightInputs, component

__all__ = ["Yang2013AttitudeHold", "yang2013_error_state"]


def yang2013_error_state(omega, q, q_desired):
    """``{"omega": e_w, "q": [e_q, e_q4]}`` of Yang2013 (7) for a desired attitude fixed in the frame of
    ``q`` (body -> frame quaternions (N, 4), vector first) and the body rate ``omega`` (N, 3) [rad/s]
    relative to that frame::

        q_e = s q_d^* (x) q,   s = sign(q_e4) (+1 at 0)                 (1) (shorter rotation)
        e_w = omega,  e_q = q_e,v,  e_q4 = q_e4 - 1                    (2)

    Every component of (2) is zero at the desired attitude, at rest, as the error state of Yang2013's
    error-level model (whose attitude error starts at zero); the signs are those with which the law (13)
    with positive gains is stabilising (the error-level plant is driven by +tau).

    Parameters
    ----------
    omega : array_like, shape (N, 3)
        Body rate relative to the frame of ``q``, body axes [rad/s].
    q : array_like, shape (N, 4)
        Body -> frame quaternions, vector first [-].
    q_desired : array_like, shape (N, 4)
        Desired body -> frame quaternions, vector first [-].

    Returns
    -------
    dict
        ``"omega"`` (N, 3) [rad/s] and ``"q"`` (N, 4) ``[e_q, e_q4]`` [-].

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.controllers.yang2013_attitude_hold import yang2013_error_state
    >>> at_rest = yang2013_error_state(np.zeros((1, 3)), np.array([[0.0, 0.0, 0.0, -1.0]]),
    ...                                np.array([[0.0, 0.0, 0.0, 1.0]]))  # -q is the same attitude
    >>> bool(np.all(np.asarray(at_rest["q"]) == 0.0))
    True
    >>> h = np.radians(60.0) / 2  # turned 60 deg about z: e_q = [0, 0, sin 30 deg], e_q4 = cos 30 deg - 1
    >>> e = yang2013_error_state(np.zeros((1, 3)), np.array([[0.0, 0.0, np.sin(h), np.cos(h)]]),
    ...                          np.array([[0.0, 0.0, 0.0, 1.0]]))
    >>> np.round(np.asarray(e["q"])[0, 2:], 6)
    array([ 0.5     , -0.133975])
    """
    qe = error_quaternion(q, q_desired)
    qe = jnp.where(qe[:, 3:4] < 0.0, -qe, qe)  # (1)
    return {"omega": omega, "q": jnp.concatenate([qe[:, 0:3], qe[:, 3:4] - 1.0], axis=-1)}  # (2)


@component
class Yang2013AttitudeHold(Controller):
    """Yang2013 attitude law (13) (``law``, its gains and inertia) towards ``desired_quaternion`` (N, 4)
    [-] (body -> state frame, vector first) on the measured quaternion state ``{"omega": (N, 3),
    "q": (N, 4)}`` of a quaternion plant (the plant's ``state_frame``; the desired attitude is at rest
    in it). Output: the body torque of (13) [N m]."""

    quantity = "torque"

    law: Yang2013AttitudeController
    desired_quaternion: Any  # (N, 4) [-]

    @property
    def count(self) -> int:
        return self.law.count

    def output(self, t, state, inputs: FlightInputs):
        m = inputs.measurement
        err = yang2013_error_state(m["omega"], m["q"], jnp.asarray(self.desired_quaternion))
        return self.law.output(t, state, inputs._replace(measurement=err))
