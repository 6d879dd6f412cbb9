"""Truth plants (translational and rotational dynamics of every spacecraft)."""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp

from formation_ftc.components.expressions import vector_expression
from formation_ftc.components.plants.relative_state import RelativeStatePlant
from formation_ftc.core.disturbances import gaussian_noise
from formation_ftc.core.dynamics.cw import cw_rhs
from formation_ftc.sim.components import Signal, TruthInputs, component, static

__all__ = ["ClohessyWiltshirePlant"]

VEC = ("spacecraft", "axis")


@component
class ClohessyWiltshirePlant(RelativeStatePlant):
    """N point-mass deputies on linear Clohessy-Wiltshire dynamics about a circular reference orbit.

    State ``{"q": (N, 6)}``, q = [x, y, z, vx, vy, vz] in LVLH (x radial, y along-track, z orbit normal)
    [m, m/s]; ``q_dot = A(n) q + B (F + d(t) + w) / m`` with the applied force F [N], the disturbance
    expressions d(t) [N] and a per-step Gaussian process-noise force w [N] (held over the step).
    """

    mean_motion: Any  # n [rad/s]
    mass: Any  # (N,) [kg]
    initial_state_lvlh: Any  # (N, 6) [m, m/s]
    process_noise_std: Any = 0.0  # [N]
    disturbance_force: tuple[str, str, str] = static(
        default=("0", "0", "0")
    )  # expressions in t, i [N]

    def exogenous(self, t):
        return {"d": vector_expression(self.disturbance_force, "disturbance.force", t, self.count)}

    def process_noise(self, key):
        return gaussian_noise(key, (self.count, 3), self.process_noise_std)

    def derivative(self, t, x, inputs: TruthInputs):
        f = inputs.force + inputs.exogenous["d"] + inputs.process_noise
        return {"q": cw_rhs(t, x["q"], f / self.mass[:, None], self.mean_motion)}

    def usage_rates(self, t, x, command):
        return {
            "delta_v": jnp.linalg.norm(command, axis=-1) / self.mass,
            "control_effort": jnp.sum(command**2, axis=-1),
        }

    def signals(self):
        return (
            Signal("position", VEC, "m", "position relative to the reference", "LVLH"),
            Signal("velocity", VEC, "m s-1", "velocity relative to the reference", "LVLH"),
            Signal("delta_v", ("spacecraft",), "m s-1", "commanded delta-v, integral of |u|/m"),
            Signal("control_effort", ("spacecraft",), "N2 s", "integral of |u|^2"),
        )

    def outputs(self, t, x, inputs):
        return {"position": x["q"][:, :3], "velocity": x["q"][:, 3:]}
