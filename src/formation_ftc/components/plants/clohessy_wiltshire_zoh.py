"""Plant ``clohessy-wiltshire-zoh``: Gui2022's plant (its (1)-(3)), linear Clohessy-Wiltshire deputies
driven by accelerations, stepped exactly (zero-order hold), with the space perturbation d(t) of its
ref. [12] (recorded: the capability ``perturbation-signal`` that ``gui2022-scores`` reads)."""

from __future__ import annotations

import dataclasses
from typing import Any

import jax.numpy as jnp
from pydantic import Field

from formation_ftc.components._registry import (
    BuildContext,
    InitialStateRows,
    builder_input,
    register,
)
from formation_ftc.components._sections import Vec3, initial_states, section_floats
from formation_ftc.components.plants._relative_state import RelativeStatePlant
from formation_ftc.core.dynamics.cw import cw_matrices_jax, cw_rhs
from formation_ftc.core.integrators import zoh_discretize_jax
from formation_ftc.core.linear import matvec
from formation_ftc.sim.components import Signal, TruthInputs, component
from formation_ftc.sim.contract import STATE, VEC, as_float

__all__ = ["ZohClohessyWiltshirePlant", "ZohCwPlantSection", "STATE_COMPONENTS"]

#: names of the six entries of a relative state q = [position, velocity]
STATE_COMPONENTS = ("x", "y", "z", "vx", "vy", "vz")


@component
class ZohClohessyWiltshirePlant(RelativeStatePlant):
    """N deputies on linear CW dynamics (Gui2022 (1)-(3)) driven by accelerations::

        q_dot = A(n) q + B (a + d(t)),   q_{k+1} = Ad q_k + Bd (a_k + d(t_k))      (exact ZOH)

    State ``{"q": (N, 6)}``, q = [x, y, z, vx, vy, vz] in LVLH (x radial, y along-track, z orbit normal)
    [m, m/s]; ``a`` the applied acceleration [m/s^2] (command plus actuator faults, held over the step);
    ``d(t) = A0 [1 - 1.5 sin nt, 0.5 sin 2nt, sin nt]`` [m/s^2] the space perturbation of Gui2022's
    ref. [12] (amplitude ``A0``; 0 disables it). ``Ad = e^{A dt}``, ``Bd = int_0^dt e^{A s} ds B`` are
    computed once per run from the mean motion leaf (:meth:`prepare`).
    """

    quantity = "acceleration"
    integration = "exact"

    mean_motion: Any  # n [rad/s]
    initial_state_lvlh: Any  # (N, 6) [m, m/s]
    disturbance_amplitude: Any = 0.0  # A0 [m/s^2]
    # set by prepare() (empty until then: no leaves): Ad (6, 6) [-], Bd (6, 3) [s]
    Ad: Any = ()
    Bd: Any = ()

    def prepare(self, dt: float) -> ZohClohessyWiltshirePlant:
        A, B = cw_matrices_jax(self.mean_motion)
        Ad, Bd = zoh_discretize_jax(A, B, dt)
        return dataclasses.replace(self, Ad=Ad, Bd=Bd)

    def exogenous(self, t):
        nt = self.mean_motion * t
        s, c = jnp.sin(nt), jnp.cos(nt)
        # 0.5 sin 2nt = sin nt cos nt
        d = self.disturbance_amplitude * jnp.stack([1.0 - 1.5 * s, s * c, s])
        return {"d": jnp.broadcast_to(d, (self.count, 3))}

    def derivative(self, t, x, inputs: TruthInputs):
        return {"q": cw_rhs(t, x["q"], inputs.force + inputs.exogenous["d"], self.mean_motion)}

    def exact_step(self, t, x, inputs: TruthInputs, dt: float):
        plant = self.prepare(dt) if isinstance(self.Ad, tuple) else self
        w = inputs.force + inputs.exogenous["d"]  # held over the step (B = E = H)
        return {"q": matvec(plant.Ad, x["q"]) + matvec(plant.Bd, w)}

    def provides(self) -> frozenset[str]:
        return super().provides() | {"perturbation-signal"}  # exact step: no stage evaluation

    def signals(self):
        return (
            Signal(
                "state",
                STATE,
                "m, m s-1",
                "relative state q (positions [m], velocities [m s-1])",
                "LVLH",
            ),
            Signal("disturbance", VEC, "m s-2", "space perturbation d", "LVLH"),
        )

    def coords(self):
        return {"component": list(STATE_COMPONENTS)}

    def outputs(self, t, x, inputs):
        return {"state": x["q"], "disturbance": inputs.exogenous["d"]}


class ZohCwPlantSection(InitialStateRows):
    """Deputies on linear CW dynamics driven by accelerations, stepped exactly (Gui2022 (1)-(3))."""

    mean_motion: float = Field(
        gt=0, description="Mean motion n of the chief's circular orbit [rad/s] (truth)."
    )
    initial_position: list[Vec3] = builder_input(
        description="Initial LVLH position per spacecraft [m]."
    )
    initial_velocity: list[Vec3] | None = builder_input(
        None, description="Initial LVLH velocity per spacecraft [m/s] (default 0)."
    )
    disturbance_amplitude: float = Field(
        0.0,
        ge=0,
        description=(
            "A0 of d(t) = A0 [1 - 1.5 sin nt, 0.5 sin 2nt, sin nt] (Gui2022's ref. [12]) [m/s^2]; 0: none."
        ),
    )


def _build(sec: ZohCwPlantSection, ctx: BuildContext) -> ZohClohessyWiltshirePlant:
    """The plant of a validated ``[plant] type = "clohessy-wiltshire-zoh"`` section."""
    return ZohClohessyWiltshirePlant(
        **section_floats(sec, "mean_motion", "disturbance_amplitude"),
        initial_state_lvlh=as_float(initial_states(sec.initial_position, sec.initial_velocity)),
    )


register(
    "plant",
    "clohessy-wiltshire-zoh",
    ZohCwPlantSection,
    _build,
    "linear CW deputies driven by accelerations, exact ZOH step, Gui2022's perturbation d(t)",
)
