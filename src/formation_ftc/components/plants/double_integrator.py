"""Plant ``double-integrator``: the deep-space formation of Azizi & Khorasani 2009 (Sec. II), N double
integrators per axis (no gravity gradient), driven by accelerations ``x_i'' = b_i u_i + d_i(t)`` (the
actuator gains b_i live in the actuator, e.g. ``actuator-gains``).

Provides the capabilities ``translational-state`` (positions ``r`` and velocities ``v``),
``spacecraft-pairs`` (two or more spacecraft) and, with ``integration = "rk4"``, ``stage-evaluation``.
"""

from __future__ import annotations

from typing import Any, Literal

import jax.numpy as jnp
import numpy as np
from pydantic import Field

from formation_ftc.components._registry import (
    BuildContext,
    InitialStateRows,
    builder_input,
    register,
)
from formation_ftc.components._sections import Vec3, initial_states
from formation_ftc.components.expressions import spacecraft_numbers
from formation_ftc.config.base import ExprText
from formation_ftc.core.dynamics.double_integrator import (
    DoubleIntegratorState,
    held_acceleration_step,
)
from formation_ftc.core.expressions import compile_expression
from formation_ftc.sim.components import Plant, Signal, TruthInputs, component, static
from formation_ftc.sim.contract import VEC, as_float

__all__ = ["DoubleIntegratorPlant", "DoubleIntegratorSection"]


@component
class DoubleIntegratorPlant(Plant):
    """N point masses on decoupled double integrators, ``n_axes`` of x, y, z::

        x_i'' = a_i + d_i(t)                                            (Azizi2009 Sec. II: a_i = b_i u_i)

    State ``{"r": (N, axes), "v": (N, axes)}`` [m, m/s] in an inertial frame; the applied acceleration
    ``a`` [m/s^2] comes from the actuator (actuator gains b_i and their faults live there);
    ``disturbance_acceleration`` d_i(t) [m/s^2] is one expression in t [s] and i (1-based spacecraft
    number), the same on every axis.
    ``zoh = True``: the exact step with the applied and disturbance accelerations held at their t_k
    values (zero-order hold); False: RK4 with the controller re-evaluated at the stages.
    Usage integral ``effort`` = int u^2 dt per spacecraft and axis of the command u.
    """

    initial_position: Any  # (N, axes) [m]
    initial_velocity: Any  # (N, axes) [m/s]
    disturbance_acceleration: str = static(default="0")  # d_i(t) [m/s^2]
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
        d = compile_expression(
            self.disturbance_acceleration, ("t", "i"), "plant.disturbance_acceleration"
        )
        per_sc = jnp.broadcast_to(d(t=t, i=spacecraft_numbers(self.count)), (self.count,))
        return {"d": per_sc[:, None] * jnp.ones((self.n_axes,))}

    def derivative(self, t, x, inputs: TruthInputs):
        return {"r": x["v"], "v": inputs.force + inputs.exogenous["d"]}

    def exact_step(self, t, x, inputs: TruthInputs, dt):
        new = held_acceleration_step(
            DoubleIntegratorState(x["r"], x["v"]), inputs.force + inputs.exogenous["d"], dt
        )
        return {"r": new.r, "v": new.v}

    def provides(self) -> frozenset[str]:
        caps = {"translational-state"} | ({"spacecraft-pairs"} if self.count >= 2 else set())
        caps |= {"stage-evaluation"} if not self.zoh else set()
        return super().provides() | caps

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


class DoubleIntegratorSection(InitialStateRows):
    """Deep space (Azizi & Khorasani 2009 Sec. II): decoupled double integrators per axis,
    ``x_i'' = a_i + d_i(t)`` with the actuator's applied acceleration ``a_i = b_i u_i`` [m/s^2]."""

    initial_position: list[Vec3] = Field(
        description="Initial inertial position per spacecraft, x, y, z [m] (the first `axes` are used)."
    )
    initial_velocity: list[Vec3] | None = Field(
        None, description="Initial inertial velocity per spacecraft, x, y, z [m/s] (default 0)."
    )
    axes: int = builder_input(
        3, ge=1, le=3, description="Simulated axes: 1 = x, 2 = x, y, 3 = x, y, z [-]."
    )
    disturbance_acceleration: ExprText = Field(
        "0",
        description="Disturbance d_i(t) on every axis, an expression in t [s] and i "
        "(1-based spacecraft number) [m/s^2].",
    )
    integration: Literal["exact", "rk4"] = builder_input(
        "exact",
        description="'exact': the exact step with the applied and disturbance accelerations held over "
        "the step (zero-order hold); 'rk4': RK4 (a 'continuous' law is re-evaluated at the stages).",
    )


def _build(sec: DoubleIntegratorSection, ctx: BuildContext) -> DoubleIntegratorPlant:
    """The plant of a validated ``[plant] type = "double-integrator"`` section."""
    q0 = initial_states(sec.initial_position, sec.initial_velocity)  # (N, 6): x, y, z, vx, vy, vz
    return DoubleIntegratorPlant(
        initial_position=as_float(q0[:, : sec.axes]),
        initial_velocity=as_float(q0[:, 3 : 3 + sec.axes]),
        disturbance_acceleration=str(sec.disturbance_acceleration),
        zoh=sec.integration == "exact",
    )


register(
    "plant",
    "double-integrator",
    DoubleIntegratorSection,
    _build,
    "deep-space double integrators x'' = b u + d(t) per axis (Azizi2009), driven by accelerations",
)
