"""Truth side of a velocity-channel controller fault (Yang2013 Sec. 4): the individual controller of a
spacecraft applies a wrong velocity gain from the fault onset on."""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp

from formation_ftc.sim.components import Actuator, ActuatorInputs, Signal, component, static

__all__ = ["VelocityGainFaultActuator"]


@component
class VelocityGainFaultActuator(Actuator):
    """Applied wrench = commanded wrench + the force error of a faulty velocity gain::

        f_applied,i = f_i + M_i (K2f_i - K2) e_V,i     for t >= t_f,i   [N]

    i.e. the force of law (12) with K2 replaced by K2f (Yang2013 Sec. 4). The fault is the truth side's:
    the flight-side law never sees it; the supervisor sees only a diagnosis. With ``reconfigurable``, a
    reconfiguration requested by the supervisor (its decision's ``reconfigure`` (N,) flag) replaces the
    faulty unit by a nominal one from that step on. The plant state must hold the (N, 13) error state
    under ``"x"`` (e_V in columns 3:6; perfect sensors make it the value the faulty unit uses).

    ``mass`` (N,) [kg]; ``K2`` nominal velocity gain [1/s]; ``K2_faulty`` (N,) [1/s]; ``onset`` (N,) t_f
    [s] on the step grid (inf: no fault).
    """

    count: int = static()
    mass: Any = 1.0
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
        gain = jnp.where(self._faulty(inputs), self.mass * (self.K2_faulty - self.K2), 0.0)
        delta = gain[:, None] * e_V
        return command + jnp.concatenate([delta, jnp.zeros_like(command[:, 3:])], axis=-1)

    def signals(self):
        return (
            Signal(
                "controller_faulty",
                ("spacecraft",),
                "1",
                "true controller fault in effect (1) or not (0), truth side",
            ),
        )

    def outputs(self, t, command, inputs: ActuatorInputs):
        return {"controller_faulty": self._faulty(inputs).astype(jnp.float64)}
