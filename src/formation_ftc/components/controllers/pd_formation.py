"""Flight-side control laws. Each reads only :class:`~formation_ftc.sim.components.FlightInputs`."""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from formation_ftc.components.expressions import vector_expression
from formation_ftc.sim.components import Controller, FlightInputs, component, static

__all__ = ["DesiredPositionLaw", "PdFormationController", "ZeroController"]

VEC = ("spacecraft", "axis")


def _desired_motion(desired_position: tuple[str, str, str], count: int, t) -> dict:
    """``{"p", "v", "a"}``: the desired LVLH position p^d(t) [m] of the expressions per axis (in t [s]
    and the 1-based spacecraft number i) and its exact time derivatives v^d [m/s], a^d [m/s^2]
    (forward-mode autodiff), each (N, 3)."""

    def p(tt):
        return vector_expression(desired_position, "controller.desired_position", tt, count)

    v = jax.jacfwd(p)
    return {"p": p(t), "v": v(t), "a": jax.jacfwd(v)(t)}


@component
class ZeroController(Controller):
    """No control (free drift): u = 0 [N]."""

    count: int = static()

    def output(self, t, state, inputs: FlightInputs):
        return jnp.zeros((self.count, 3)), None, {}


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
        return _desired_motion(self.desired_position, self.count, t)

    def desired_position_at(self, exogenous):
        return exogenous["p"]


@component
class PdFormationController(DesiredPositionLaw):
    """PD formation keeping with feed-forward on measured relative states [N]::

        u_i = -kp (p_i - p_i^d(t)) - kd (v_i - v_i^d(t)) + m_i a_i^d(t)

    ``p^d(t)``, v^d and a^d as in :class:`DesiredPositionLaw`. ``mass`` is the nominal mass the law uses
    [kg]; ``max_force`` saturates each axis [N] (inf: none). ``is_sampled``: held over the step (ZOH)."""

    kp: Any = 0.0  # [N/m]
    kd: Any = 0.0  # [N s/m]
    mass: Any = 1.0  # (N,) nominal masses [kg]
    max_force: Any = float("inf")  # [N]

    def output(self, t, state, inputs: FlightInputs):
        y, d = inputs.measurement, inputs.exogenous
        u = (
            -self.kp * (y[:, :3] - d["p"])
            - self.kd * (y[:, 3:] - d["v"])
            + self.mass[:, None] * d["a"]
        )
        u = jnp.clip(u, -self.max_force, self.max_force)
        return u, None, {}
