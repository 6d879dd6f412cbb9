"""Actuator chain on the truth side: faults (and saturation) between command and applied output."""

from __future__ import annotations

from formation_ftc.components.expressions import vector_expression
from formation_ftc.core.faults import actuator_fault
from formation_ftc.sim.components import Actuator, ActuatorInputs, Signal, component, static

__all__ = ["ExpressionFaultActuator"]


class EffectivenessBiasActuator(Actuator):
    """Applied = Gamma(t) * command + delta(t) per axis from the time signals ``{"gamma", "bias"}`` of
    the subclass's :meth:`exogenous`; records the effectiveness Gamma(t)."""

    def apply(self, t, command, inputs: ActuatorInputs):
        return actuator_fault(command, inputs.exogenous["gamma"], inputs.exogenous["bias"])

    def signals(self):
        return (
            Signal("effectiveness", ("spacecraft", "axis"), "1", "actuator effectiveness Gamma(t)"),
        )

    def outputs(self, t, command, inputs: ActuatorInputs):
        return {"effectiveness": inputs.exogenous["gamma"]}


@component
class ExpressionFaultActuator(EffectivenessBiasActuator):
    """Applied = Gamma(t) * command + delta(t) per axis (loss of effectiveness and additive bias),
    both written as expressions in t [s] and i (1-based spacecraft number)."""

    count: int = static()
    effectiveness: tuple[str, str, str] = static(default=("1", "1", "1"))  # Gamma(t) [-]
    bias: tuple[str, str, str] = static(default=("0", "0", "0"))  # delta(t) [command units]

    def exogenous(self, t):
        return {
            "gamma": vector_expression(self.effectiveness, "faults.effectiveness", t, self.count),
            "bias": vector_expression(self.bias, "faults.bias", t, self.count),
        }
