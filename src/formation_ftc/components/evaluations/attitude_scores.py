"""Evaluation ``attitude-scores``: scores of an attitude formation that every attitude law is judged by
alike (truth side): attitude error against a common desired attitude, pairwise synchronisation error
and applied torque.

The desired attitude is the evaluator's own (N, 4) leaf, not the law's, so laws that state their
objective differently (Euler angles, quaternions, a synchronisation target) are scored against the
same attitude. Angles are rotation angles of relative quaternions, independent of any Euler sequence.
Needs the capability ``quaternion-attitude-state`` (and ``lvlh-attitude`` for a desired attitude in
LVLH).
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np
from pydantic import Field

from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.components._sections import UnitQuaternions, quaternion_rows
from formation_ftc.config.base import StrictModel
from formation_ftc.core.quaternion import quat_conjugate, quat_multiply
from formation_ftc.sim.components import Evaluation, Signal, component, static
from formation_ftc.sim.contract import as_float

__all__ = ["AttitudeScores", "AttitudeScoresSection", "rotation_angle", "relative_angle"]


def rotation_angle(q):
    """Rotation angle of the unit quaternion(s) ``q`` (..., 4), vector first, in ``[0, pi]`` [rad]::

        theta = 2 atan2(|q_v|, |q4|)                                     (1)

    (the shorter rotation: q and -q give the same angle).

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternion(s), vector first [-].

    Returns
    -------
    jax.Array, shape (...)
        theta [rad].

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.evaluations.attitude_scores import rotation_angle
    >>> h = np.radians(90.0) / 2
    >>> q = np.array([[0.0, 0.0, np.sin(h), np.cos(h)], [0.0, 0.0, -np.sin(h), -np.cos(h)]])
    >>> np.degrees(np.asarray(rotation_angle(q))).round(6)  # q and -q: the same 90 deg
    array([90., 90.])
    """
    return 2.0 * jnp.arctan2(jnp.linalg.norm(q[..., 0:3], axis=-1), jnp.abs(q[..., 3]))  # (1)


def relative_angle(p, q):
    """Angle of the rotation from attitude ``p`` to attitude ``q`` (..., 4) [rad]: (1) of ``p^* (x) q``.

    Parameters
    ----------
    p, q : array_like, shape (..., 4)
        Unit quaternions, vector first [-].

    Returns
    -------
    jax.Array, shape (...)
        The angle in ``[0, pi]`` [rad].

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.evaluations.attitude_scores import relative_angle
    >>> def about_x(deg):
    ...     h = np.radians(deg) / 2
    ...     return np.array([np.sin(h), 0.0, 0.0, np.cos(h)])
    >>> round(float(np.degrees(relative_angle(about_x(10.0), about_x(35.0)))), 6)
    25.0
    """
    return rotation_angle(quat_multiply(quat_conjugate(p), q))


@component
class AttitudeScores(Evaluation):
    """Signals, at every sample:

    * ``attitude_error`` (N,) [rad]: rotation angle between each body attitude and its desired attitude;
    * ``attitude_synchronisation_error`` () [rad]: max over pairs i < j of the rotation angle between the
      attitudes of i and j (0 when all point alike, whatever the common attitude);
    * ``torque`` (N,) [N m]: ||tau_i||, the applied body torque (after saturation and faults).

    ``desired_quaternion`` (N, 4) [-]: desired body -> frame quaternions, vector first, in the frame of
    the recorded attitude signal ``attitude_signal`` (static: ``"quaternion"``, the body -> inertial
    attitude, or ``"attitude_lvlh"``, body -> LVLH). Reads that signal and the loop's ``applied``.
    """

    desired_quaternion: Any  # (N, 4) [-]
    attitude_signal: str = static(default="quaternion")

    def signals(self):
        return (
            Signal(
                "attitude_error", ("spacecraft",), "rad", "rotation angle from the desired attitude"
            ),
            Signal(
                "attitude_synchronisation_error",
                (),
                "rad",
                "max over pairs of the rotation angle between two spacecraft's attitudes",
            ),
            Signal("torque", ("spacecraft",), "N m", "norm of the applied body torque"),
        )

    def outputs(self, signals):
        q = signals[self.attitude_signal]
        n = q.shape[-2]
        err = relative_angle(jnp.asarray(self.desired_quaternion), q)
        if n > 1:
            iu, ju = np.triu_indices(n, k=1)
            sync = jnp.max(relative_angle(q[..., iu, :], q[..., ju, :]), axis=-1)
        else:
            sync = jnp.zeros(q.shape[:-2])
        return {
            "attitude_error": err,
            "attitude_synchronisation_error": sync,
            "torque": jnp.linalg.norm(signals["applied"], axis=-1),
        }

    def needs(self) -> dict[str, str]:
        out = {"quaternion-attitude-state": "score its attitudes and torques"}
        if self.attitude_signal == "attitude_lvlh":
            out["lvlh-attitude"] = "score the attitudes against a desired attitude in LVLH"
        return out


class AttitudeScoresSection(StrictModel):
    """Attitude error, pairwise synchronisation error and applied torque against a common attitude."""

    desired_quaternion: UnitQuaternions = Field(
        None,
        description="Desired attitude body -> `frame`, one unit quaternion [q1, q2, q3, q4] (vector first) "
        "or one per spacecraft [-] (default identity).",
    )
    frame: str = builder_input(
        "state",
        description="Frame of desired_quaternion: 'inertial', 'lvlh' or 'state' (the "
        "plant's state_frame).",
    )


def _build(sec: AttitudeScoresSection, ctx: BuildContext) -> AttitudeScores:
    """The evaluation of a validated ``[[evaluations]] type = "attitude-scores"`` section."""
    frame = sec.frame
    # "state": the frame of the plant's attitude state (a plant that does not say: inertial)
    if frame == "state":
        frame = str(getattr(ctx.section("plant"), "state_frame", "inertial"))
    signal = {"inertial": "quaternion", "lvlh": "attitude_lvlh"}.get(frame)
    if signal is None:
        raise ValueError(f"evaluations.frame = {sec.frame!r}: one of 'inertial', 'lvlh', 'state'")
    q = quaternion_rows(sec.desired_quaternion, ctx.count, "evaluations.desired_quaternion")
    return AttitudeScores(desired_quaternion=as_float(q), attitude_signal=signal)


register(
    "evaluation",
    "attitude-scores",
    AttitudeScoresSection,
    _build,
    "attitude error against a common attitude, pairwise synchronisation error, applied torque",
)
