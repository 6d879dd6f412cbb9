"""Estimator ``scheduled-diagnosis``: a fault detection and isolation (FDI) unit modelled by its
diagnosis times, the onsets of the ``velocity-gain-fault`` actuator's faults plus a stated delay
(Yang2013; none without such faults). The ``switching`` supervisor counts the delay as the a-priori
bound in dt2 of (29)."""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np

from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.components.actuators.velocity_gain_fault import _fault_steps
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import Estimator, FlightInputs, Signal, component, static
from formation_ftc.sim.contract import as_float

__all__ = ["ScheduledDiagnosis", "ScheduledDiagnosisSection"]


@component
class ScheduledDiagnosis(Estimator):
    """FDI model: the fault of spacecraft i is diagnosed from ``diagnosis_time[i]`` [s] on (the fault
    onset plus the unit's diagnosis delay; inf: never) and stays diagnosed. The flight side receives only
    this diagnosis, ``{"diagnosed": (N,) bool}``, never the fault itself. Times are compared with the
    step times t_k, so they should lie on the step grid."""

    count: int = static()
    diagnosis_time: Any = float("inf")

    def initial_state(self, measurement0):
        return {"diagnosed": jnp.zeros(self.count, dtype=bool)}

    def update(self, t, state, inputs: FlightInputs):
        est = {"diagnosed": state["diagnosed"] | (t >= self.diagnosis_time)}
        return est, est

    def signals(self):
        return (
            Signal(
                "fault_diagnosed",
                ("spacecraft",),
                "1",
                "fault diagnosed by the FDI unit (flight side)",
            ),
        )

    def outputs(self, t, state, estimate):
        return {"fault_diagnosed": estimate["diagnosed"].astype(jnp.float64)}


class ScheduledDiagnosisSection(StrictModel):
    """FDI unit modelled by its diagnosis delay after the actuator's fault onsets."""

    delay: float = builder_input(
        0.0,
        ge=0,
        description="Diagnosis delay after the fault onset [s] (snapped to the step grid); the "
        "switching supervisor counts it as the a-priori bound in dt2 of (29).",
    )


def _build(sec: ScheduledDiagnosisSection, ctx: BuildContext) -> ScheduledDiagnosis:
    """The estimator of a validated ``[estimator] type = "scheduled-diagnosis"`` section."""
    delay = round(sec.delay / ctx.dt)  # [steps]
    diagnosis = np.full(ctx.count, np.inf)
    for s, (k_f, _) in _fault_steps(ctx).items():
        diagnosis[s] = (k_f + delay) * ctx.dt
    return ScheduledDiagnosis(count=ctx.count, diagnosis_time=as_float(diagnosis))


register(
    "estimator",
    "scheduled-diagnosis",
    ScheduledDiagnosisSection,
    _build,
    "FDI unit diagnosing the actuator's faults after a stated delay",
)
