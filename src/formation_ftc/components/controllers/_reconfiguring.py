"""A force law behind a reconfiguring allocation: the force commanded of a thruster channel that the
estimator isolated and identified is divided by its identified effectiveness, up to the rated thrust
(Zhang & Jiang, *Bibliographical review on reconfigurable fault-tolerant control systems*, 2008: control
reallocation with the effectiveness an FDI estimates)."""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np

from formation_ftc.components.controllers._acceleration_to_force import WrappedLaw, wrapper_for
from formation_ftc.components.estimators.residual_fdi import isolated_effectiveness
from formation_ftc.sim.components import CompositionError, Controller, FlightInputs, component

__all__ = ["ReconfiguringAllocator", "TrackingReconfiguringAllocator", "reconfigured"]

#: the wrapped law's command, recorded next to the loop's ``command`` (the reallocated force)
LAW_COMMAND_SIGNAL = "law_command"


@component
class ReconfiguringAllocator(WrappedLaw):
    """The force law ``law`` with its command reallocated with the estimator's fault identification::

        f_ij = clip(u_ij / effectiveness_ij, -force_limit, force_limit)   on the channel the FDI isolated
                                                                           and identified
        f_ij = u_ij                                                        elsewhere, and before that

    with the identified effectiveness clipped to [0.05, 1]
    (:func:`~formation_ftc.components.estimators.residual_fdi.isolated_effectiveness`) (a channel identified
    above 1 gets its command unchanged). Each spacecraft has one thruster channel per axis, so the
    force the law asks of a weakened channel can only be asked of that channel: a loss of effectiveness
    is compensated up to the rated thrust ``force_limit`` [N] (flight knowledge; inf: none), an outage
    cannot be (its effectiveness is at the floor and its command at the rating). Records the law's own
    command as ``law_command``. Needs ``fault-identification``.
    """

    force_limit: Any  # () rated thrust per axis [N]

    quantity = "force"
    recorded_command = (
        LAW_COMMAND_SIGNAL,
        "N",
        "force commanded by the law (before the reallocation)",
    )

    def __post_init__(self) -> None:
        law = self.law
        if isinstance(law, Controller) and law.quantity != "force":
            raise CompositionError(
                f"ReconfiguringAllocator reallocates a force command, but controller "
                f"{type(law).__name__} commands a {law.quantity}"
            )

    def needs(self) -> dict[str, str]:
        return {
            **self.law.needs(),
            "fault-identification": "reallocate the command with the identified effectiveness",
        }

    def command(self, u, inputs: FlightInputs):
        use, eff = isolated_effectiveness(inputs.estimate)
        return jnp.where(use, jnp.clip(u / eff, -self.force_limit, self.force_limit), u)


@component
class TrackingReconfiguringAllocator(ReconfiguringAllocator):
    """:class:`ReconfiguringAllocator` for a law with a position objective (``position_error``)."""

    def desired_position_at(self, exogenous):
        return self.law.desired_position_at(exogenous)


def reconfigured(law: Controller, force_limit: float) -> ReconfiguringAllocator:
    """``law`` (a force law) behind a :class:`ReconfiguringAllocator` with the rated thrust
    ``force_limit`` [N] (inf: none); its position objective, if it declares one, is kept.

    Parameters
    ----------
    law : Controller
        A law with ``quantity = "force"``.
    force_limit : float
        Rated thrust per axis [N], > 0.

    Returns
    -------
    ReconfiguringAllocator
        A :class:`TrackingReconfiguringAllocator` when ``law`` declares a desired position.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.controllers.none import FreeDrift
    >>> from formation_ftc.components.controllers._acceleration_to_force import force_from_acceleration
    >>> ctrl = reconfigured(force_from_acceleration(FreeDrift(count=2), np.array([1.0, 1.0])), 0.2)
    >>> type(ctrl).__name__, ctrl.quantity, sorted(ctrl.needs())
    ('ReconfiguringAllocator', 'force', ['fault-identification'])
    """
    cls = wrapper_for(law, ReconfiguringAllocator, TrackingReconfiguringAllocator)
    return cls(law=law, force_limit=np.float64(force_limit))
