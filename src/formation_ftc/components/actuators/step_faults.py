"""Actuator with numeric step losses of effectiveness (Monte Carlo friendly: values are leaves)."""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np

from formation_ftc.components.actuators.expression_faults import EffectivenessBiasActuator
from formation_ftc.components.expressions import vector_expression
from formation_ftc.sim.components import component, static

__all__ = ["StepFaultActuator"]


@component
class StepFaultActuator(EffectivenessBiasActuator):
    """Applied = Gamma(t) * command + delta(t) per axis with a step loss of effectiveness::

        alpha_ij(t) = alpha_ij  for t >= onset_ij,  1 before                (Li2020 eq. (5))

    ``alpha`` (N, 3) [-] and ``onset`` (N, 3) [s] are array leaves, so a campaign varies them without
    recompiling; the additive fault delta(t) is written as expressions in t [s] and i."""

    alpha: Any  # (N, 3) effectiveness after the onset, in (0, 1] [-]
    onset: Any  # (N, 3) onset times [s]
    bias: tuple[str, str, str] = static(default=("0", "0", "0"))  # delta(t) [command units]

    @property
    def count(self) -> int:
        return int(np.shape(self.alpha)[0])

    def exogenous(self, t):
        return {
            "gamma": jnp.where(t >= self.onset, self.alpha, 1.0),
            "bias": vector_expression(self.bias, "faults.additive", t, self.count),
        }
