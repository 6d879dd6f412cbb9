"""Flight-side control laws. Each reads only :class:`~formation_ftc.sim.components.FlightInputs`."""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from formation_ftc.components.expressions import vector_expression
from formation_ftc.sim.components import Controller, FlightInputs, component, static

__all__ = ["PdFormationController", "ZeroController"]

VEC = ("spacecraft", "axis")


@component
class ZeroController(Controller):
    """No control (free drift): u = 0 [N]."""

    count: int = static()

    def output(self, t, state, inputs: FlightInputs):
        return jnp.zeros((self.count, 3)), None, {}


@component
class PdFormationController(Controller):
    """PD formation keeping with feed-forward on measured relative states [N]::

        u_i = -kp (p_i - p_i^d(t)) - kd (v_i - v_i^d(t)) + m_i a_i^d(t)

    ``p^d(t)`` is an expression per axis (in t [s] and the 1-based spacecraft number i); v^d and a^d are
    its exact time derivatives (forward-mode autodiff). ``mass`` is the nominal mass the law uses [kg];
    ``max_force`` saturates each axis [N] (inf: none). ``is_sampled``: held over the step (ZOH)."""

    count: int = static()
    kp: Any = 0.0  # [N/m]
    kd: Any = 0.0  # [N s/m]
    mass: Any = 1.0  # (N,) nominal masses [kg]
    max_force: Any = float("inf")  # [N]
    desired_position: tuple[str, str, str] = static(default=("0", "0", "0"))
    is_sampled: bool = static(default=False)

    @property
    def sampled(self) -> bool:
        return self.is_sampled

    def _desired(self, t):
        def p(tt):
            return vector_expression(self.desired_position, "controller.desired_position", tt, self.count)
        v = jax.jacfwd(p)
        a = jax.jacfwd(v)
        return p(t), v(t), a(t)

    def exogenous(self, t):
        p, v, a = self._desired(t)
        return {"p": p, "v": v, "a": a}

    def desired_position_at(self, exogenous):
        return exogenous["p"]

    def output(self, t, state, inputs: FlightInputs):
        y, d = inputs.measurement, inputs.exogenous
        u = -self.kp * (y[:, :3] - d["p"]) - self.kd * (y[:, 3:] - d["v"]) + self.mass[:, None] * d["a"]
        u = jnp.clip(u, -self.max_force, self.max_force)
        return u, None, {}


