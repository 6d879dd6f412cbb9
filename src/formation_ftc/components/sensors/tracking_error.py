"""Sensors of an error-level formation: each spacecraft's deviation from its desired relative state and
its attitude error."""

from __future__ import annotations

from formation_ftc.sim.components import SensorInputs, Sensors, component, static

__all__ = ["TrackingErrorSensors"]


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
