"""Shared base of the formation laws that track a desired LVLH position written as expressions
(``pd``, ``lqr``, Yang2013's translational laws, plug-ins)."""

from __future__ import annotations

import jax

from formation_ftc.components.expressions import vector_expression
from formation_ftc.sim.components import Controller, component, static

__all__ = ["DesiredPositionLaw", "desired_motion"]


def desired_motion(desired_position: tuple[str, str, str], count: int, t) -> dict:
    """The desired LVLH motion of the expressions per axis.

    Parameters
    ----------
    desired_position : tuple of str
        p^d(t) per axis, expressions in t [s] and the 1-based spacecraft number i [m].
    count : int
        Number of spacecraft N.
    t : float or jax.Array
        Time [s].

    Returns
    -------
    dict
        ``{"p", "v", "a"}``: p^d(t) [m] and its exact time derivatives v^d [m/s], a^d [m/s^2]
        (forward-mode autodiff), each (N, 3).

    Examples
    --------
    >>> import numpy as np
    >>> d = desired_motion(("t**2", "0", "i"), 2, 3.0)
    >>> np.asarray(d["p"]).tolist(), np.asarray(d["v"])[:, 0].tolist(), np.asarray(d["a"])[:, 0].tolist()
    ([[9.0, 0.0, 1.0], [9.0, 0.0, 2.0]], [6.0, 6.0], [2.0, 2.0])
    """

    def p(tt):
        return vector_expression(desired_position, "controller.desired_position", tt, count)

    v = jax.jacfwd(p)
    return {"p": p(t), "v": v(t), "a": jax.jacfwd(v)(t)}


@component
class DesiredPositionLaw(Controller):
    """Base of the formation laws that track a desired LVLH position given as expressions.

    ``p^d(t)`` is an expression per axis (in t [s] and the 1-based spacecraft number i) [m]; v^d [m/s]
    and a^d [m/s^2] are its exact time derivatives (forward-mode autodiff), delivered as the time-only
    signals ``{"p", "v", "a"}`` (each (N, 3)). ``is_sampled``: the law is held over the step (ZOH)."""

    count: int = static()
    desired_position: tuple[str, str, str] = static(default=("0", "0", "0"))
    is_sampled: bool = static(default=False)

    @property
    def sampled(self) -> bool:
        return self.is_sampled

    def exogenous(self, t):
        return desired_motion(self.desired_position, self.count, t)

    def desired_position_at(self, exogenous):
        return exogenous["p"]
