"""Sensors ``lvlh-relative-state``: the deputies' state relative to the chief in the chief's LVLH frame,
with held Gaussian noise and a constant per-axis bias.

Needs the plant's ``lvlh-relative-state`` (the (N, 6) relative state in what sensors see: the
relative-motion plants, and the inertial truth ``orbital-truth``, whose sensed state is already the
LVLH relative state). Provides ``chain-outputs``: a chain law or supervisor forms its chain outputs on
board from this measurement.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.components._sections import per_axis, section_floats
from formation_ftc.components.sensors.relative_state import (
    RelativeStateSection,
    RelativeStateSensors,
)
from formation_ftc.core.dynamics.orbital_truth import eci_to_lvlh
from formation_ftc.sim.components import SensorInputs, Sensors, component, static
from formation_ftc.sim.contract import as_float

__all__ = ["LvlhRelativeStateSensors", "LvlhRelativeStateSection"]


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

    def needs(self) -> dict[str, str]:
        return {"lvlh-relative-state": "measure it"}

    def provides(self) -> frozenset[str]:
        return frozenset({"chain-outputs", "relative-state-measurement"})

    def measure(self, t, x, inputs: SensorInputs):
        q = x["q"] if "q" in x else eci_to_lvlh(x["chief"], x["deputies"])
        return q + inputs.noise + self.bias


class LvlhRelativeStateSection(RelativeStateSection):
    """Relative state in the truth chief's LVLH frame with held Gaussian noise and a constant bias
    (``bias`` of the component: position and velocity bias side by side, (N, 6))."""

    position_bias: float | list = builder_input(
        0.0, description="Constant position bias: a number, 3 values (per axis) or N x 3 [m]."
    )
    velocity_bias: float | list = builder_input(
        0.0, description="Constant velocity bias: a number, 3 values or N x 3 [m/s]."
    )


def _build(sec: LvlhRelativeStateSection, ctx: BuildContext) -> LvlhRelativeStateSensors:
    """The sensors of a validated ``[sensors] type = "lvlh-relative-state"`` section."""
    n = ctx.count
    position_bias = per_axis(sec.position_bias, n, "sensors.position_bias")
    bias = np.hstack([position_bias, per_axis(sec.velocity_bias, n, "sensors.velocity_bias")])
    if not np.all(np.isfinite(bias)):
        raise ValueError("sensors.position_bias / velocity_bias: values must be finite")
    return LvlhRelativeStateSensors(
        count=n,
        **section_floats(sec, "position_noise_std", "velocity_noise_std"),
        bias=as_float(bias),
    )


register(
    "sensors",
    "lvlh-relative-state",
    LvlhRelativeStateSection,
    _build,
    "relative state in the truth chief's LVLH frame with held Gaussian noise and a "
    "constant per-axis bias",
)
