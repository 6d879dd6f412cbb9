"""Shared base of the actuators that apply a loss of effectiveness and an additive bias per axis
(``expression-faults``, ``step-faults``)."""

from __future__ import annotations

from formation_ftc.core.faults import actuator_fault
from formation_ftc.sim.components import Actuator, ActuatorInputs, Signal
from formation_ftc.sim.contract import VEC

__all__ = ["EffectivenessBiasActuator"]


class EffectivenessBiasActuator(Actuator):
    """Applied = Gamma(t) * command + delta(t) per axis from the time signals ``{"gamma", "bias"}`` of
    the subclass's :meth:`exogenous`; records the effectiveness Gamma(t)."""

    def apply(self, t, command, inputs: ActuatorInputs):
        return actuator_fault(command, inputs.exogenous["gamma"], inputs.exogenous["bias"])

    def signals(self):
        return (Signal("effectiveness", VEC, "1", "actuator effectiveness Gamma(t)"),)

    def outputs(self, t, command, inputs: ActuatorInputs):
        return {"effectiveness": inputs.exogenous["gamma"]}
