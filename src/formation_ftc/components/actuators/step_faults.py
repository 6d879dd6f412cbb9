"""Actuator ``step-faults``: numeric step losses of effectiveness per spacecraft and axis and additive
bias expressions (Monte Carlo friendly: the numbers are array leaves)."""

from __future__ import annotations

from typing import Any, cast

import jax.numpy as jnp
import numpy as np
from pydantic import Field, model_validator

from formation_ftc.components._registry import BuildContext, register
from formation_ftc.components._sections import Vec3, Vec3Expr
from formation_ftc.components.actuators._effectiveness_bias import EffectivenessBiasActuator
from formation_ftc.components.expressions import vector_expression
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import component, static
from formation_ftc.sim.contract import as_float

__all__ = ["StepFaultActuator", "StepFaultSection"]


@component
class StepFaultActuator(EffectivenessBiasActuator):
    """Applied = Gamma(t) * command + delta(t) per axis with a step loss of effectiveness::

        alpha_ij(t) = alpha_ij  for t >= onset_ij,  1 before                (Li2020 eq. (5))

    ``effectiveness`` alpha_ij (N, 3) [-] and ``onset`` (N, 3) [s] are array leaves, so a campaign
    varies them without recompiling; the additive fault delta(t) is written as expressions in t [s]
    and i."""

    effectiveness: Any  # (N, 3) alpha_ij, effectiveness after the onset, in (0, 1] [-]
    onset: Any  # (N, 3) onset times [s]
    bias: tuple[str, str, str] = static(default=("0", "0", "0"))  # delta(t) [command units]

    @property
    def count(self) -> int:
        return int(np.shape(self.effectiveness)[0])

    def exogenous(self, t):
        return {
            "gamma": jnp.where(t >= self.onset, self.effectiveness, 1.0),
            "bias": vector_expression(self.bias, "faults.additive", t, self.count),
        }


class StepFaultSection(StrictModel):
    """alpha_ij(t) = effectiveness[i][j] from onset[i][j] on, 1 before (Li2020 eq. (5)); numbers, not
    expressions, so that campaigns vary them without recompiling."""

    effectiveness: list[Vec3] = Field(
        description="Effectiveness after the onset per spacecraft and axis, in (0, 1] [-] (N x 3)."
    )
    onset: list[Vec3] = Field(
        description="Onset per spacecraft and axis, >= 0 [s] (N x 3; snapped to the step grid)."
    )
    bias: Vec3Expr = Field(
        ("0", "0", "0"), description="Additive fault per axis, expressions in t, i [N]."
    )

    @model_validator(mode="after")
    def _ranges(self):
        for name, ok, rng, unit in (
            ("effectiveness", lambda v: 0.0 < v <= 1.0, "(0, 1]", "-"),
            ("onset", lambda v: v >= 0.0, ">= 0", "s"),
        ):
            for i, row in enumerate(getattr(self, name)):
                for j, v in enumerate(row):
                    if not ok(v):
                        raise ValueError(f"{name}[{i}][{j}] = {v}: must be {rng} [{unit}]")
        return self


def _build(sec: StepFaultSection, ctx: BuildContext) -> StepFaultActuator:
    """The actuator of a validated ``[actuator] type = "step-faults"`` section."""
    for name in ("effectiveness", "onset"):
        rows = len(getattr(sec, name))
        if rows != ctx.count:
            raise ValueError(f"actuator.{name}: {rows} rows for {ctx.count} spacecraft (N x 3)")
    # onsets snapped to the step grid so that no RK step straddles a fault onset
    onset = np.round(np.asarray(sec.onset, float) / ctx.dt) * ctx.dt
    return StepFaultActuator(
        effectiveness=as_float(sec.effectiveness),
        onset=as_float(onset),
        bias=cast(Vec3Expr, tuple(sec.bias)),
    )


register(
    "actuator",
    "step-faults",
    StepFaultSection,
    _build,
    "step loss of effectiveness per spacecraft and axis (numbers) and additive bias expressions",
)
