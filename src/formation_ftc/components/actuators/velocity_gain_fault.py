"""Actuator ``velocity-gain-fault``: the truth side of a velocity-channel controller fault (Yang2013
Sec. 4): the individual controller of a spacecraft applies a wrong velocity gain K2 -> K2f from the
fault onset on, reconfigurable by the supervisor.

The faulty unit is the law's own: it uses the nominal K2 and the stated mass M_i of the
``[controller]`` section (the capability ``velocity-gain-law``, ``yang2013-force-torque``).
"""

from __future__ import annotations

from typing import Any, Literal

import jax.numpy as jnp
import numpy as np
from pydantic import Field

from formation_ftc.components._registry import BuildContext, builder_input, per_spacecraft, register
from formation_ftc.components._sections import grid_steps
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import Actuator, ActuatorInputs, Signal, component, static
from formation_ftc.sim.contract import as_float

__all__ = ["VelocityGainFaultActuator", "VelocityFault", "VelocityGainFaultSection"]


@component
class VelocityGainFaultActuator(Actuator):
    """Applied wrench = commanded wrench + the force error of a faulty velocity gain::

        f_applied,i = f_i + M_i (K2f_i - K2) e_V,i     for t >= t_f,i   [N]

    i.e. the force of law (12) with K2 replaced by K2f (Yang2013 Sec. 4). The fault is the truth side's:
    the flight-side law never sees it; the supervisor sees only a diagnosis. With ``reconfigurable``, a
    reconfiguration requested by the supervisor (its decision's ``reconfigure`` (N,) flag) replaces the
    faulty unit by a nominal one from that step on. The plant state must hold the (N, 13) error state
    under ``"x"`` (e_V in columns 3:6; perfect sensors make it the value the faulty unit uses).

    ``nominal_mass`` (N,) M_i [kg] (the law's stated mass); ``K2`` nominal velocity gain [1/s];
    ``K2_faulty`` (N,) [1/s]; ``onset`` (N,) t_f [s] on the step grid (inf: no fault).
    """

    count: int = static()
    nominal_mass: Any = 1.0
    K2: Any = 0.01
    K2_faulty: Any = 0.0
    onset: Any = float("inf")
    reconfigurable: bool = static(default=True)

    def exogenous(self, t):
        return {"faulty": t >= self.onset}

    def _faulty(self, inputs: ActuatorInputs):
        faulty = inputs.exogenous["faulty"]
        reconf = getattr(inputs.decision, "reconfigure", None)
        if self.reconfigurable and reconf is not None:
            faulty = faulty & ~reconf
        active = getattr(inputs.decision, "active", None)
        if active is not None:
            faulty = faulty & (active > 0)
        return faulty

    def apply(self, t, command, inputs: ActuatorInputs):
        e_V = inputs.plant_state["x"][:, 3:6]
        gain = jnp.where(self._faulty(inputs), self.nominal_mass * (self.K2_faulty - self.K2), 0.0)
        delta = gain[:, None] * e_V
        return command + jnp.concatenate([delta, jnp.zeros_like(command[:, 3:])], axis=-1)

    def signals(self):
        in_effect = "true controller fault in effect (1) or not (0), truth side"
        return (Signal("controller_faulty", ("spacecraft",), "1", in_effect),)

    def outputs(self, t, command, inputs: ActuatorInputs):
        return {"controller_faulty": self._faulty(inputs).astype(jnp.float64)}

    def needs(self) -> dict[str, str]:
        return {"velocity-gain-law": "replace its velocity gain K2 by the faulty K2f"}


class VelocityFault(StrictModel):
    """Velocity-channel controller fault K2 -> K2f (Yang2013 Sec. 4)."""

    spacecraft: int = Field(ge=1, description="Faulty spacecraft number [-].")
    onset: float = Field(ge=0, description="Fault onset time t_f [s] (a multiple of the step).")
    K2_faulty: float = Field(-0.01, description="Faulty velocity gain K2f [1/s].")


class VelocityGainFaultSection(StrictModel):
    """Controller faults of the truth side; the faulty unit uses the law's K2 and stated mass."""

    faults: list[VelocityFault] = builder_input(
        default_factory=list, description="Controller faults (none: a healthy unit)."
    )
    reconfiguration: Literal["restore_nominal", "none"] = builder_input(
        "restore_nominal",
        description="What a reconfiguration request of the supervisor does: the reconfigured "
        "controller uses the nominal K2 ('restore_nominal', ideal) or nothing changes ('none').",
    )


def _fault_steps(ctx: BuildContext) -> dict[int, tuple[int, float]]:
    """Slot -> (onset step, K2f) of the ``[actuator]``'s velocity-gain faults (none for another
    actuator), checked against the slots and the step grid.

    Parameters
    ----------
    ctx : BuildContext
        The build's context (the actuator section, the spacecraft count, the step [s]).

    Returns
    -------
    dict
        0-based slot -> (onset step [-], K2f [1/s]).
    """
    sec = ctx.section("actuator")
    out: dict[int, tuple[int, float]] = {}
    if not isinstance(sec, VelocityGainFaultSection):
        return out
    for f in sec.faults:
        if f.spacecraft > ctx.count:
            raise ValueError(
                f"actuator.faults: spacecraft {f.spacecraft} exceeds plant.count = {ctx.count}"
            )
        k_f = grid_steps(f.onset, ctx.dt, "actuator.faults: onset")
        out[f.spacecraft - 1] = (k_f, f.K2_faulty)
    return out


def _build(sec: VelocityGainFaultSection, ctx: BuildContext) -> VelocityGainFaultActuator:
    """The actuator of a validated ``[actuator] type = "velocity-gain-fault"`` section: the faulty
    law's extra force M_i (K2f - K2) e_V with the ``[controller]``'s K2 and stated mass (without them
    a placeholder, which the loop refuses: it needs ``velocity-gain-law``)."""
    law = ctx.section("controller")
    K2, mass = getattr(law, "K2", 0.0), getattr(law, "nominal_mass", 1.0)
    n = ctx.count
    onset = np.full(n, np.inf)
    K2f = np.full(n, K2)
    for s, (k_f, k2f) in _fault_steps(ctx).items():
        onset[s], K2f[s] = k_f * ctx.dt, k2f  # on the step grid: t_k as the loop computes it
    return VelocityGainFaultActuator(
        count=n,
        nominal_mass=as_float(per_spacecraft(mass, n, "controller.nominal_mass")),
        K2=as_float(K2),
        K2_faulty=as_float(K2f),
        onset=as_float(onset),
        reconfigurable=sec.reconfiguration == "restore_nominal",
    )


register(
    "actuator",
    "velocity-gain-fault",
    VelocityGainFaultSection,
    _build,
    "controller fault K2 -> K2f of the law (12) (Yang2013 Sec. 4), reconfigurable",
)
