"""Formation errors on a chain of spacecraft pairs, and a threshold flag (evaluation signals)."""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp

from formation_ftc.core.polygon_formation import chain_difference
from formation_ftc.sim.components import Evaluation, Signal, component, static

__all__ = ["ChainTrackingError", "ThresholdFlag"]


@component
class ChainTrackingError(Evaluation):
    """True relative tracking errors on the chain pairs (1, 2), ..., (N-1, N) [m]::

        tracking_error_ij = (x_j - x_i) - (x_j^d - x_i^d)

    from the plant's ``position`` and the controller's ``desired_position`` signals (N, axes)."""

    def signals(self):
        return (
            Signal(
                "tracking_error",
                ("pair", "axis"),
                "m",
                "true relative tracking error e_ij = (x_j - x_i) - (x_j^d - x_i^d)",
            ),
        )

    def outputs(self, signals):
        return {
            "tracking_error": chain_difference(signals["position"])
            - chain_difference(signals["desired_position"])
        }


@component
class ThresholdFlag(Evaluation):
    """``name = source >= threshold`` (a boolean signal, e.g. a metric gate)."""

    name: str = static()
    source: str = static()
    long_name: str = static(default="")
    threshold: Any = 0.0

    def signals(self):
        return (Signal(self.name, (), "1", self.long_name or f"{self.source} >= threshold"),)

    def outputs(self, signals):
        return {self.name: jnp.logical_not(jnp.asarray(signals[self.source]) < self.threshold)}
