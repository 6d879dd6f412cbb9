"""Evaluation ``fdi-scores``: truth-side scores of a fault detection and isolation component (records
and metrics only): detection delay, missed detection, false alarm and isolation against the true fault.

Needs ``fdi-records`` (a fault detector recording its alarm and isolation, e.g. ``residual-fdi``) and
``true-actuator-fault`` (the ``fault-battery`` actuator's record of the true fault).
"""

from __future__ import annotations

import jax.numpy as jnp

from formation_ftc.components._registry import BuildContext, register
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import Evaluation, Signal, component

__all__ = ["FdiScores", "FdiScoresSection"]


@component
class FdiScores(Evaluation):
    """Compares the FDI's latched alarm and isolation (``fdi_detected``, ``fdi_isolated``) with the
    actuator's true fault (``fault_active``, ``fault_channel`` of the fault-battery actuator). Signals,
    at every sample (1 or 0):

    * ``fdi_pending``: the fault is active and not yet detected -- its time integral is the detection
      delay [s] (up to the horizon when it is never detected);
    * ``fdi_missed``: the same, read at the horizon (``reduce = "last"``): 1 = missed detection;
    * ``fdi_false_alarm``: an alarm while no fault is active (``reduce = "max"``: 1 = a false alarm;
      over no-fault runs, their fraction per hour of flight is the false-alarm rate);
    * ``fdi_correct_isolation``: detected, a fault active, and the isolated channel is the faulty one.
    """

    def needs(self) -> dict[str, str]:
        return {
            "fdi-records": "compare its alarm with the true fault",
            "true-actuator-fault": "score the fault detector against it",
        }

    def signals(self):
        return (
            Signal("fdi_pending", (), "1", "fault active and not yet detected"),
            Signal("fdi_missed", (), "1", "fault active and not detected (read at the horizon)"),
            Signal("fdi_false_alarm", (), "1", "alarm without an active fault"),
            Signal("fdi_correct_isolation", (), "1", "alarm isolating the faulty channel"),
        )

    def outputs(self, signals):
        active = signals["fault_active"] > 0.5
        detected = signals["fdi_detected"] > 0.5
        channel = signals["fault_channel"] > 0.5
        isolated = signals["fdi_isolated"] > 0.5
        pending = jnp.where(active & ~detected, 1.0, 0.0)
        right = detected & active & jnp.all(isolated == channel)
        return {
            "fdi_pending": pending,
            "fdi_missed": pending,
            "fdi_false_alarm": jnp.where(detected & ~active, 1.0, 0.0),
            "fdi_correct_isolation": jnp.where(right, 1.0, 0.0),
        }


class FdiScoresSection(StrictModel):
    """Truth-side FDI scores (no fields)."""


def _build(sec: FdiScoresSection, ctx: BuildContext) -> FdiScores:
    """The evaluation of a validated ``[[evaluations]] type = "fdi-scores"`` item."""
    return FdiScores()


register(
    "evaluation",
    "fdi-scores",
    FdiScoresSection,
    _build,
    "detection delay, missed detection, false alarm and isolation of an FDI against the true fault",
)
