"""Evaluation ``formation-scores``: scores of a translational formation that every control law is judged
by alike (truth side): slot and shape errors, thrust and delivered acceleration against common slots.

The desired slots are the evaluator's own (N, 3) leaf, not the law's desired trajectory, so laws that
describe the formation differently (a rotating circle, a chain of relative offsets, explicit slots) are
scored against the same geometry.
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np
from pydantic import Field

from formation_ftc.components._registry import BuildContext, per_spacecraft, register
from formation_ftc.components._sections import Vec3
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import Evaluation, Signal, component, static
from formation_ftc.sim.contract import as_float

__all__ = ["FormationScores", "FormationScoresSection", "shape_error"]


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
    true masses (``mass_from_plant``: the plant's, :meth:`needs` them). Reads the plant's ``position``
    and the loop's ``applied`` signals (:meth:`needs`: a plant that records positions and is driven by
    forces)."""

    desired: Any  # (N, 3) [m]
    mass: Any  # (N,) [kg]
    mass_from_plant: bool = static(default=False)

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

    def needs(self) -> dict[str, str]:
        out = {
            "recorded-positions": "score each spacecraft's slot and the formation's shape",
            "applied-forces": "score the applied thrust",
        }
        if self.mass_from_plant:
            out["true-masses"] = (
                "turn the thrust into the delivered acceleration (no evaluations.mass)"
            )
        return out


class FormationScoresSection(StrictModel):
    """Slot error, shape error, thrust and delivered acceleration against common desired slots."""

    desired: list[Vec3] = Field(
        description="Desired slot of each spacecraft in the plant's formation frame [m]."
    )
    mass: float | list[float] | None = Field(
        None, description="True masses [kg] (default: the plant's `mass`)."
    )


def _build(sec: FormationScoresSection, ctx: BuildContext) -> FormationScores:
    """The evaluation of a validated ``[[evaluations]] type = "formation-scores"`` table."""
    n = ctx.count
    desired = np.asarray(sec.desired, dtype=float)
    if desired.shape != (n, 3):
        raise ValueError(f"evaluations.desired: {len(sec.desired)} slots for {n} spacecraft")
    mass = sec.mass if sec.mass is not None else getattr(ctx.plant, "mass", None)
    # without masses (refused by needs()): a placeholder of the right shape
    m = per_spacecraft(1.0 if mass is None else mass, n, "evaluations.mass")
    if np.any(~(m > 0)):
        raise ValueError(f"evaluations.mass = {list(m)}: every mass must be > 0 [kg]")
    return FormationScores(
        desired=as_float(desired), mass=as_float(m), mass_from_plant=sec.mass is None
    )


register(
    "evaluation",
    "formation-scores",
    FormationScoresSection,
    _build,
    "slot error, shape error, applied thrust and delivered acceleration against common slots",
)
