"""Evaluation signal per unit mass: a recorded force divided by each spacecraft's true mass."""

from __future__ import annotations

from typing import Any

from formation_ftc.sim.components import Evaluation, Signal, component, static
from formation_ftc.sim.contract import VEC

__all__ = ["PerUnitMass"]


@component
class PerUnitMass(Evaluation):
    """``name = signal / m_i`` per spacecraft i: an (N, 3) force [N] divided by the true mass
    ``mass`` (N,) [kg] gives an acceleration [m/s^2] (e.g. a thruster fault in the units of an
    observer's fault estimate). Truth side: for records and metrics only."""

    name: str = static()
    signal: str = static()
    mass: Any = 1.0  # (N,) [kg]
    dims: tuple[str, ...] = static(default=VEC)
    units: str = static(default="m s-2")
    long_name: str = static(default="")
    frame: str | None = static(default=None)

    def signals(self):
        return (Signal(self.name, self.dims, self.units, self.long_name, self.frame),)

    def outputs(self, signals):
        return {self.name: signals[self.signal] / self.mass[:, None]}
