"""Scores of a translational formation that every control law is judged by alike (truth side).

The desired slots are the evaluator's own (N, 3) leaf, not the law's desired trajectory, so laws that
describe the formation differently (a rotating circle, a chain of relative offsets, explicit slots) are
scored against the same geometry.
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np

from formation_ftc.sim.components import Evaluation, Signal, component

__all__ = ["FormationScores", "shape_error"]


def shape_error(rho: jnp.ndarray, desired: jnp.ndarray) -> jnp.ndarray:
    """max over pairs i < j of ||(rho_i - rho_j) - (d_i - d_j)|| [m]; rho, desired (..., N, 3).

    The formation-keeping error: it ignores a common translation of the whole formation (a law that keeps
    the shape while the formation drifts as a whole scores 0 here, not on the slot error).

    Parameters
    ----------
    rho : array_like, shape (..., N, 3)
        Positions [m].
    desired : array_like, shape (..., N, 3)
        Desired slots [m].

    Returns
    -------
    jax.Array, shape (...)
        The shape error [m].

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.evaluations.formation_scores import shape_error
    >>> desired = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 10.0, 0.0]])
    >>> float(shape_error(desired + 7.0, desired))  # a common drift
    0.0
    >>> float(shape_error(desired + np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 2.0], [0.0, 0.0, 0.0]]), desired))
    2.0
    """
    n = rho.shape[-2]
    iu, ju = np.triu_indices(n, k=1)
    c = rho - desired
    return jnp.max(jnp.linalg.norm(c[..., iu, :] - c[..., ju, :], axis=-1), axis=-1)


@component
class FormationScores(Evaluation):
    """Signals, at every sample:

    * ``slot_error`` (N,) [m]: ||rho_i - d_i||, distance of each spacecraft from its desired slot;
    * ``shape_error`` () [m]: :func:`shape_error`, the formation-keeping error;
    * ``thrust`` (N,) [N]: ||F_i||, the applied force (after saturation and faults);
    * ``applied_acceleration`` (N,) [m/s^2]: ||F_i|| / m_i (its time integral is the delta-v actually
      delivered, unlike the plant's ``delta_v`` which integrates the command).

    ``desired`` (N, 3) [m] are the slots in the plant's formation frame (LVLH), ``mass`` (N,) [kg] the
    true masses. Reads the plant's ``position`` and the loop's ``applied`` signals."""

    desired: Any  # (N, 3) [m]
    mass: Any  # (N,) [kg]

    def signals(self):
        return (
            Signal("slot_error", ("spacecraft",), "m", "distance from the desired slot"),
            Signal(
                "shape_error",
                (),
                "m",
                "formation-keeping error, max over pairs of the relative-position error",
            ),
            Signal("thrust", ("spacecraft",), "N", "norm of the applied force"),
            Signal(
                "applied_acceleration",
                ("spacecraft",),
                "m s-2",
                "norm of the applied force per unit mass",
            ),
        )

    def outputs(self, signals):
        rho = signals["position"]
        force = jnp.linalg.norm(signals["applied"], axis=-1)
        return {
            "slot_error": jnp.linalg.norm(rho - self.desired, axis=-1),
            "shape_error": shape_error(rho, self.desired),
            "thrust": force,
            "applied_acceleration": force / self.mass,
        }
