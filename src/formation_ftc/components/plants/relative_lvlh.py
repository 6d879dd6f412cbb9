"""Plant ``relative-lvlh``: nonlinear relative translational motion about an elliptic Keplerian
reference orbit (the ``[reference]``), in its LVLH frame (Li2020 eqs. (1)-(4))."""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
from pydantic import Field

from formation_ftc.components._registry import BuildContext, register
from formation_ftc.components.expressions import vector_expression
from formation_ftc.components.plants._relative_state import (
    PointMassSection,
    PointMassUsage,
    RelativeStatePlant,
)
from formation_ftc.core.constants import MU_EARTH
from formation_ftc.core.dynamics.relative_lvlh import natural_acceleration_from_rates
from formation_ftc.sim.components import Signal, TruthInputs, component, static
from formation_ftc.sim.contract import VEC, as_float

__all__ = ["RelativeLvlhPlant", "RelativeLvlhSection"]


@component
class RelativeLvlhPlant(PointMassUsage, RelativeStatePlant):
    """N point-mass spacecraft on the nonlinear relative dynamics of Li2020 eqs. (1)-(4).

    State ``{"q": (N, 6)}``, q = [x, y, z, vx, vy, vz] in LVLH (x radial, y along-track, z orbit normal)
    [m, m/s]. Per spacecraft i (mass m_i [kg])::

        rho_dot_i = v_i                                                        (E000-02)
        v_dot_i   = (C_i v_i + D_i rho_i + n_i) / m_i + (h_i(t) + F_i) / m_i    (eq. (1))

    with the applied force F_i [N] (after the actuator's faults), the disturbance expressions h_i(t)
    [N] and the reference-orbit values r_c, theta_dot, theta_ddot of a
    :class:`~formation_ftc.components.references.keplerian.KeplerianReference` (required:
    :meth:`needs`).
    """

    mass: Any  # (N,) [kg]
    initial_state_lvlh: Any  # (N, 6) [m, m/s]
    mu: Any  # gravitational parameter [m^3/s^2]
    #: h_i(t), expressions in t, i [N]
    disturbance_force: tuple[str, str, str] = static(default=("0", "0", "0"))

    def exogenous(self, t):
        return {"h": vector_expression(self.disturbance_force, "disturbance.force", t, self.count)}

    def derivative(self, t, x, inputs: TruthInputs):
        ref = inputs.reference
        q = x["q"]
        rho, v = q[:, :3], q[:, 3:]
        acc_nat = natural_acceleration_from_rates(
            rho, v, ref["r_c"], ref["theta_dot"], ref["theta_ddot"], self.mu
        )  # eqs. (2)-(4) / m_i
        acc = acc_nat + (inputs.exogenous["h"] + inputs.force) / self.mass[:, None]  # eq. (1)
        return {"q": jnp.concatenate([v, acc], axis=-1)}

    def signals(self):
        return (
            Signal("position", VEC, "m", "position rho_i relative to the reference", "LVLH"),
            Signal("velocity", VEC, "m s-1", "velocity v_i relative to the reference", "LVLH"),
            Signal("true_anomaly", (), "rad", "true anomaly of the reference orbit"),
            Signal("delta_v", ("spacecraft",), "m s-1", "commanded delta-v, integral of |f_i|/m_i"),
            Signal("control_effort", ("spacecraft",), "N2 s", "integral of |f_i|^2"),
        )

    def outputs(self, t, x, inputs):
        return {
            "position": x["q"][:, :3],
            "velocity": x["q"][:, 3:],
            "true_anomaly": inputs.reference["theta"],
        }

    def needs(self) -> dict[str, str]:
        return {"reference-orbit": "integrate the relative motion about it (eqs. (1)-(4))"}


class RelativeLvlhSection(PointMassSection):
    """Point masses on the nonlinear relative dynamics about the ``[reference]`` orbit."""

    mu: float = Field(MU_EARTH, gt=0, description="Gravitational parameter [m^3/s^2].")


def _build(sec: RelativeLvlhSection, ctx: BuildContext) -> RelativeLvlhPlant:
    """The plant of a validated ``[plant] type = "relative-lvlh"`` section."""
    return RelativeLvlhPlant(
        mass=as_float(sec.mass),
        initial_state_lvlh=as_float(sec.q0()),
        mu=as_float(sec.mu),
        disturbance_force=sec.disturbance_force,
    )


register(
    "plant",
    "relative-lvlh",
    RelativeLvlhSection,
    _build,
    "nonlinear relative motion about an elliptic reference orbit (needs [reference])",
)
