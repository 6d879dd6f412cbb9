"""Controller ``yang2013-attitude``: Yang2013's attitude law (13) holding a fixed attitude of a
quaternion plant.

:class:`~formation_ftc.components.controllers._yang2013.Yang2013AttitudeController` reads the
error state ``(e_w, e_q, e_q4)`` of Yang2013 (7), zero at the desired attitude. This component forms that
error state from a quaternion plant's measured state and hands it to the law unchanged. The gains of
the ``yang2013`` scenarios are the defaults (K3 = 0.2, K4 = K5 = 1 [1/s], kappa = 1e-3 [rad^2/s^2]);
the desired attitude is fixed in the plant's ``state_frame`` (inertial hold, or LVLH hold with
``state_frame = "lvlh"``). It reads the plant state (body rate and body -> frame quaternion) unchanged:
no ``[sensors]`` (the capabilities ``quaternion-attitude-state`` and ``plant-state-measurement``).
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
from pydantic import Field

from formation_ftc.components._flight_defaults import NOMINAL_INERTIA
from formation_ftc.components._registry import BuildContext, register
from formation_ftc.components._sections import Inertia, UnitQuaternions, quaternion_rows
from formation_ftc.components.controllers._yang2013 import Yang2013AttitudeController, attitude_law
from formation_ftc.components.controllers.attitude_pd import QUATERNION_LAW_NEEDS, error_quaternion
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import Controller, FlightInputs, component
from formation_ftc.sim.contract import as_float

__all__ = ["Yang2013AttitudeHold", "Yang2013AttitudeSection", "yang2013_error_state"]


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
    >>> from formation_ftc.components.controllers.yang2013_attitude import yang2013_error_state
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

    def needs(self) -> dict[str, str]:
        return dict(QUATERNION_LAW_NEEDS)


class Yang2013AttitudeSection(StrictModel):
    """Yang2013 attitude law (13), drift term cancelled, towards the state frame's axes."""

    K3: float = Field(0.2, gt=0.0, description="Angular-rate gain K3 [1/s].")
    K4: float = Field(1.0, gt=0.0, description="Quaternion-vector shaping gain K4 [1/s].")
    K5: float = Field(1.0, gt=0.0, description="Quaternion-scalar shaping gain K5 [1/s].")
    kappa: float = Field(1e-3, gt=0.0, description="Smoothing constant kappa of (13) [rad^2/s^2].")
    nominal_inertia: Inertia = Field(
        NOMINAL_INERTIA,
        description="Principal inertia of the law's model, known on board [kg m^2] (default 25, 25, "
        "25 kg m^2, Yang2013's spacecraft, a stated value: never the plant's true inertia).",
    )
    desired_quaternion: UnitQuaternions = Field(
        None,
        description="Desired attitude, body -> state frame, one unit quaternion [q1, q2, q3, q4] (vector "
        "first) or one per spacecraft [-] (default identity: aligned with the state frame).",
    )


def _build(sec: Yang2013AttitudeSection, ctx: BuildContext) -> Yang2013AttitudeHold:
    """The controller of a validated ``[controller] type = "yang2013-attitude"`` section."""
    law = attitude_law(ctx, sec)
    q_d = quaternion_rows(sec.desired_quaternion, ctx.count, "controller.desired_quaternion")
    return Yang2013AttitudeHold(law=law, desired_quaternion=as_float(q_d))


register(
    "controller",
    "yang2013-attitude",
    Yang2013AttitudeSection,
    _build,
    "Yang2013 attitude law (13) on a quaternion plant's state (holds the state frame's axes)",
)
