"""Deep-space formation: N double integrators per axis (no gravity gradient; Azizi & Khorasani 2009)."""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np

from formation_ftc.components.expressions import spacecraft_numbers
from formation_ftc.core.dynamics.double_integrator import (
    DoubleIntegratorState,
    held_acceleration_step,
)
from formation_ftc.core.expressions import compile_expression
from formation_ftc.sim.components import Plant, Signal, TruthInputs, component, static

__all__ = ["DoubleIntegratorPlant"]

VEC = ("spacecraft", "axis")


@component
class DoubleIntegratorPlant(Plant):
    """N point masses on decoupled double integrators, ``n_axes`` of x, y, z::

        x_i'' = a_i + d_i(t)                                            (Azizi2009 Sec. II: a_i = b_i u_i)

    State ``{"r": (N, axes), "v": (N, axes)}`` [m, m/s] in an inertial frame; the applied acceleration
    ``a`` [m/s^2] comes from the actuator (actuator gains b_i and their faults live there); ``d_i(t)``
    [m/s^2] is one expression in t [s] and i (1-based spacecraft number), the same on every axis.
    ``zoh = True``: the exact step with the applied and disturbance accelerations held at their t_k
    values (zero-order hold); False: RK4 with the controller re-evaluated at the stages.
    Usage integral ``effort`` = int u^2 dt per spacecraft and axis of the command u.
    """

    initial_position: Any  # (N, axes) [m]
    initial_velocity: Any  # (N, axes) [m/s]
    disturbance: str = static(default="0")  # d_i(t) [m/s^2]
    zoh: bool = static(default=True)

    quantity = "acceleration"

    @property
    def integration(self) -> str:  # type: ignore[override]
        return "exact" if self.zoh else "rk4"

    @property
    def count(self) -> int:
        return int(np.shape(self.initial_position)[0])

    @property
    def n_axes(self) -> int:
        return int(np.shape(self.initial_position)[1])

    def initial_state(self):
        return {"r": self.initial_position, "v": self.initial_velocity}

    def exogenous(self, t):
        d = compile_expression(self.disturbance, ("t", "i"), "disturbance.acceleration")
        per_sc = jnp.broadcast_to(d(t=t, i=spacecraft_numbers(self.count)), (self.count,))
        return {"d": per_sc[:, None] * jnp.ones((self.n_axes,))}

    def derivative(self, t, x, inputs: TruthInputs):
        return {"r": x["v"], "v": inputs.force + inputs.exogenous["d"]}

    def exact_step(self, t, x, inputs: TruthInputs, dt):
        new = held_acceleration_step(
            DoubleIntegratorState(x["r"], x["v"]), inputs.force + inputs.exogenous["d"], dt
        )
        return {"r": new.r, "v": new.v}

    def position(self, x):
        return x["r"]

    def velocity(self, x):
        return x["v"]

    def usage_names(self):
        return ("effort",)

    def usage_shape(self):
        return (self.count, self.n_axes)

    def usage_rates(self, t, x, command):
        return {"effort": command * command}

    def signals(self):
        return (
            Signal("position", VEC, "m", "position", "inertial"),
            Signal("velocity", VEC, "m s-1", "velocity", "inertial"),
            Signal(
                "effort",
                VEC,
                "m2 s-3",
                "cumulative effort E_i = int u_i^2 dt of the command u",
                "inertial",
            ),
        )

    def outputs(self, t, x, inputs):
        return {"position": x["r"], "velocity": x["v"]}
