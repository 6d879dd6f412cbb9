"""Evaluation signals built by arithmetic on recorded signals: signed sums (truth minus estimate,
synthesized disturbances) and the Euclidean norm of part of a vector (position part of a state error).

They are computed at every step for the metrics and at every record; the flight side never sees them.
"""

from __future__ import annotations

import jax.numpy as jnp

from formation_ftc.sim.components import Evaluation, Signal, component, static
from formation_ftc.sim.contract import VEC

__all__ = ["SignalSum", "PartNorm"]


@component
class SignalSum(Evaluation):
    """``name = s_1 a_1 + s_2 a_2 + ...`` for signals ``a_i`` of one shape and signs ``s_i`` in {"+", "-"},
    evaluated left to right (e.g. ``(("+", "fault"), ("-", "fault_estimate"))``: the estimation error)."""

    name: str = static()
    terms: tuple[tuple[str, str], ...] = static()
    dims: tuple[str, ...] = static(default=VEC)
    units: str = static(default="1")
    long_name: str = static(default="")
    frame: str | None = static(default=None)

    def __post_init__(self) -> None:
        if not self.terms or any(sign not in ("+", "-") for sign, _ in self.terms):
            raise ValueError(
                f"evaluation {self.name!r}: terms must be (sign, signal) pairs with sign '+' or '-'"
            )

    def signals(self):
        return (Signal(self.name, self.dims, self.units, self.long_name, self.frame),)

    def outputs(self, signals):
        (sign0, name0), *rest = self.terms
        v = signals[name0] if sign0 == "+" else -signals[name0]
        for sign, name in rest:
            v = v + signals[name] if sign == "+" else v - signals[name]
        return {self.name: v}


@component
class PartNorm(Evaluation):
    """``name = || signal[..., start:stop] ||`` (Euclidean norm over part of the last axis)."""

    name: str = static()
    signal: str = static()
    start: int = static(default=0)
    stop: int = static(default=3)
    dims: tuple[str, ...] = static(default=("spacecraft",))
    units: str = static(default="1")
    long_name: str = static(default="")

    def signals(self):
        return (Signal(self.name, self.dims, self.units, self.long_name),)

    def outputs(self, signals):
        v = signals[self.signal][..., self.start : self.stop]
        return {self.name: jnp.sqrt(jnp.sum(v * v, axis=-1))}
