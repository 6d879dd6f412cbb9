"""A fault detection and isolation (FDI) unit modelled by its diagnosis times."""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp

from formation_ftc.sim.components import Estimator, FlightInputs, Signal, component, static

__all__ = ["ScheduledDiagnosis"]


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
