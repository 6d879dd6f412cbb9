"""Sensors of an inertial truth plant: the deputies' state relative to the chief, in the chief's LVLH frame."""

from __future__ import annotations

from typing import Any

from formation_ftc.components.sensors.relative_state import RelativeStateSensors
from formation_ftc.core.dynamics.orbital_truth import eci_to_lvlh
from formation_ftc.sim.components import SensorInputs, Sensors, component, static

__all__ = ["LvlhRelativeStateSensors"]


@component
class LvlhRelativeStateSensors(Sensors):
    """Relative position and velocity of every deputy in the truth chief's LVLH frame, with additive
    Gaussian noise drawn once per step (held over the step) and a constant bias::

        y_i = eci_to_lvlh(x_chief, x_i) + [n_p, n_v] + b_i        [m, m/s]

    The loop hands sensors the plant's sensed state: for
    :class:`~formation_ftc.components.plants.orbital_truth.InertialFormationPlant` that is already the LVLH
    relative state ``{"q": (N, 6)}``; given the inertial state itself (``"chief"`` (6,) and ``"deputies"``
    (N, 6) in ECI) the sensor maps it.
    The output has the layout of
    :class:`~formation_ftc.components.sensors.relative_state.RelativeStateSensors` ((N, 6), x radial,
    y along-track, z orbit normal), and the noise is drawn the same way from the step's key, so laws
    built for relative-state sensors run unchanged."""

    count: int = static()  # number of spacecraft
    position_noise_std: Any = 0.0  # [m]
    velocity_noise_std: Any = 0.0  # [m/s]
    bias: Any = 0.0  # (N, 6) or broadcastable: constant bias [m, m/s]

    noise = RelativeStateSensors.noise  # the same draw from the step's key

    def measure(self, t, x, inputs: SensorInputs):
        q = x["q"] if "q" in x else eci_to_lvlh(x["chief"], x["deputies"])
        return q + inputs.noise + self.bias

    def provides(self) -> frozenset[str]:
        return frozenset({"relative-state-measurement"})
