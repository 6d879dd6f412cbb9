"""Evaluation ``identification-scores``: truth-side scores of a fault identification (records and
metrics only): how far the identified effectiveness of the faulty channel is from the true one, how
long it takes to come within 10 % of it, and false identifications on healthy channels.

Needs ``fault-identification`` (an estimator that identifies each channel's effectiveness, e.g.
``residual-fdi`` with ``identification = "rls"``, recording ``fdi_effectiveness``) and
``true-actuator-fault`` (the ``fault-battery`` actuator's record of the true fault and effectiveness).
"""

from __future__ import annotations

import jax.numpy as jnp

from formation_ftc.components._registry import BuildContext, register
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import Evaluation, Signal, component

__all__ = [
    "IdentificationScores",
    "IdentificationScoresSection",
    "WITHIN",
    "WITHIN_ABSOLUTE",
    "HEALTHY_BAND",
]

#: relative error of the identified effectiveness that counts as identified (10 %) ...
WITHIN = 0.1
#: ... or this absolute error, for a true effectiveness at or near 0 (an outage) [-]
WITHIN_ABSOLUTE = 0.01
#: an identified healthy channel outside 1 +- this is a false identification
HEALTHY_BAND = 0.1


@component
class IdentificationScores(Evaluation):
    """Compares the identified effectiveness ``fdi_effectiveness`` (NaN where a channel is not yet
    identified) with the actuator's true ``effectiveness`` on the faulty channel ``fault_channel`` while
    the fault is active (``fault_active``). Signals, at every sample:

    * ``id_effectiveness_error`` [-]: |identified - true| effectiveness of the faulty channel while
      the fault is active and the channel is identified, NaN otherwise (its last finite value is the
      identification error at the end of the run);
    * ``id_pending`` (1 or 0): the fault is active and its channel's identified effectiveness is not
      within :data:`WITHIN` (10 %) of the true one, nor within :data:`WITHIN_ABSOLUTE` (0.01) of it
      (an outage's true effectiveness is 0; not identified counts as not within) -- its time
      integral is the time the identification was off by more than 10 % after the onset (the time to
      identify within 10 % when it stays there once reached);
    * ``id_false`` (1 or 0): a channel that is not faulty (or any channel while no fault is active) is
      identified with an effectiveness outside 1 +- :data:`HEALTHY_BAND`.
    """

    def needs(self) -> dict[str, str]:
        return {
            "fault-identification": "compare its identified effectiveness with the true one",
            "true-actuator-fault": "score the identification against it",
        }

    def signals(self):
        return (
            Signal(
                "id_effectiveness_error",
                (),
                "1",
                "|identified - true| effectiveness of the faulty channel (NaN: not identified)",
            ),
            Signal("id_pending", (), "1", "fault active and not identified within 10 %"),
            Signal("id_false", (), "1", "a healthy channel identified outside 1 +- 0.1"),
        )

    def outputs(self, signals):
        active = signals["fault_active"] > 0.5
        faulty = (signals["fault_channel"] > 0.5) & active
        identified = jnp.asarray(signals["fdi_effectiveness"])  # (N, 3), NaN: not identified
        true = jnp.asarray(signals["effectiveness"])
        n_axes = true.shape[-1]
        identified = identified[..., :n_axes]
        error = jnp.abs(identified - true)
        on_fault = jnp.where(faulty, error, jnp.inf)
        err = jnp.min(on_fault)  # the faulty channel's error (inf: none, or not identified)
        known = jnp.isfinite(err)
        scale = jnp.max(jnp.where(faulty, jnp.abs(true), 0.0))
        within = known & (err <= jnp.maximum(WITHIN * scale, WITHIN_ABSOLUTE))
        healthy_off = ~faulty & (jnp.abs(identified - 1.0) > HEALTHY_BAND)  # NaN compares False
        return {
            "id_effectiveness_error": jnp.where(known, err, jnp.nan),
            "id_pending": jnp.where(active & ~within, 1.0, 0.0),
            "id_false": jnp.where(jnp.any(healthy_off), 1.0, 0.0),
        }


class IdentificationScoresSection(StrictModel):
    """Scores of a fault identification against the true fault (no fields)."""


def _build(sec: IdentificationScoresSection, ctx: BuildContext) -> IdentificationScores:
    return IdentificationScores()


register(
    "evaluation",
    "identification-scores",
    IdentificationScoresSection,
    _build,
    "identification error, time to identify within 10 % and false identifications, against the true fault",
)
