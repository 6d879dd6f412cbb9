"""Actuator ``expression-faults``: loss of effectiveness and additive bias per axis, both written as
expressions (truth side)."""

from __future__ import annotations

from pydantic import Field

from formation_ftc.components._registry import BuildContext, register
from formation_ftc.components._sections import Vec3Expr
from formation_ftc.components.actuators._effectiveness_bias import EffectivenessBiasActuator
from formation_ftc.components.expressions import vector_expression
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import component, static

__all__ = ["ExpressionFaultActuator", "ExpressionFaultSection"]


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


class ExpressionFaultSection(StrictModel):
    """Gamma(t) and delta(t) per axis, expressions in t [s] and i."""

    effectiveness: Vec3Expr = Field(
        ("1", "1", "1"), description="Gamma(t) per axis, expressions in t, i [-]."
    )
    bias: Vec3Expr = Field(
        ("0", "0", "0"), description="Additive fault per axis, expressions in t, i [N]."
    )


def _build(sec: ExpressionFaultSection, ctx: BuildContext) -> ExpressionFaultActuator:
    """The actuator of a validated ``[actuator] type = "expression-faults"`` section."""
    return ExpressionFaultActuator(count=ctx.count, effectiveness=sec.effectiveness, bias=sec.bias)


register(
    "actuator",
    "expression-faults",
    ExpressionFaultSection,
    _build,
    "loss of effectiveness and additive bias written as expressions",
)
