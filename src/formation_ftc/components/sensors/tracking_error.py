"""Sensors ``tracking-error``: each spacecraft's deviation from its desired relative state and its
attitude error, read from the error state of the ``switched-formation`` plant (the capability
``error-state``); they provide the measured error state the Yang2013 laws act on
(``error-state-measurement``)."""

from __future__ import annotations

from formation_ftc.components._registry import BuildContext, register
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import SensorInputs, Sensors, component, static

__all__ = ["TrackingErrorSensors", "TrackingErrorSection"]


@component
class TrackingErrorSensors(Sensors):
    """Perfect measurement of the error state (7) held under ``"x"`` (N, 13) by the plant
    (:class:`~formation_ftc.components.plants.switched_formation.SwitchedFormationPlant`), formed on
    board from the spacecraft's own sensors and the main spacecraft's broadcast state.

    Output ``{"translation": (N, 6), "omega": (N, 3), "q": (N, 4)}``: the relative position and
    velocity *with respect to the desired relative state* (actual minus desired, so ``-[e_R, e_V]``
    [m, m/s]; a translational law whose desired trajectory is zero forms e_R = 0 - y exactly) and the
    attitude error (e_omega [rad/s], (e_q, e_q4) [-]) as the attitude law (13) uses it.
    """

    count: int = static()

    def measure(self, t, x, inputs: SensorInputs):
        X = x["x"]
        return {"translation": -X[:, 0:6], "omega": X[:, 6:9], "q": X[:, 9:13]}

    def needs(self) -> dict[str, str]:
        return {"error-state": "measure it"}

    def provides(self) -> frozenset[str]:
        return frozenset({"error-state-measurement"})


class TrackingErrorSection(StrictModel):
    """Exact measurement of the error state; no fields."""


def _build(sec: TrackingErrorSection, ctx: BuildContext) -> TrackingErrorSensors:
    """The sensors of a validated ``[sensors] type = "tracking-error"`` section."""
    return TrackingErrorSensors(count=ctx.count)


register("sensors", "tracking-error", TrackingErrorSection, _build, "exact error state")
