"""Noise-free relative-state sensors."""

from __future__ import annotations

from formation_ftc.sim.components import SensorInputs, Sensors, component, static

__all__ = ["ExactRelativeStateSensors"]


@component
class ExactRelativeStateSensors(Sensors):
    """The measured (N, 6) relative state is the true one: y = q = [position, velocity] [m, m/s].

    The plant state must hold the (N, 6) relative state under ``"q"``. No noise is drawn (cheaper than
    :class:`~formation_ftc.components.sensors.relative_state.RelativeStateSensors` with zero noise)."""

    count: int = static()  # number of spacecraft

    def measure(self, t, x, inputs: SensorInputs):
        return x["q"]

    def provides(self) -> frozenset[str]:
        return frozenset({"relative-state-measurement"})
