"""Sensors ``relative-state``: the relative position and velocity of every spacecraft, with Gaussian
noise held over each step, or exact (noise-free) when both noise levels are 0."""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
from pydantic import Field

from formation_ftc.components._registry import BuildContext, register
from formation_ftc.components._sections import section_floats
from formation_ftc.config.base import StrictModel
from formation_ftc.core.disturbances import gaussian_noise
from formation_ftc.sim.components import SensorInputs, Sensors, component, static

__all__ = ["RelativeStateSensors", "ExactRelativeStateSensors", "RelativeStateSection"]


@component
class RelativeStateSensors(Sensors):
    """Relative position and velocity of every spacecraft with additive Gaussian noise drawn once per
    step (held over the step): y = [q[:, :3] + n_p, q[:, 3:] + n_v] [m, m/s]. The plant state must
    hold the (N, 6) relative state under ``"q"``."""

    count: int = static()  # number of spacecraft
    position_noise_std: Any = 0.0  # [m]
    velocity_noise_std: Any = 0.0  # [m/s]

    def noise(self, key):
        k_p, k_v = jax.random.split(key, 2)
        position = gaussian_noise(k_p, (self.count, 3), self.position_noise_std)
        velocity = gaussian_noise(k_v, (self.count, 3), self.velocity_noise_std)
        return jnp.concatenate([position, velocity], axis=-1)

    def measure(self, t, x, inputs: SensorInputs):
        return x["q"] + inputs.noise

    def provides(self) -> frozenset[str]:
        return frozenset({"relative-state-measurement"})


@component
class ExactRelativeStateSensors(Sensors):
    """The measured (N, 6) relative state is the true one: y = q = [position, velocity] [m, m/s].

    The plant state must hold the (N, 6) relative state under ``"q"``. No noise is drawn (cheaper than
    :class:`RelativeStateSensors` with zero noise); the noise levels are 0 by construction (static)."""

    count: int = static()  # number of spacecraft
    position_noise_std: float = static(default=0.0)  # [m]
    velocity_noise_std: float = static(default=0.0)  # [m/s]

    def measure(self, t, x, inputs: SensorInputs):
        return x["q"]

    def provides(self) -> frozenset[str]:
        return frozenset({"relative-state-measurement"})


class RelativeStateSection(StrictModel):
    """Noise levels of the relative-state measurement (both 0: the exact state, no noise drawn)."""

    position_noise_std: float = Field(0.0, ge=0, description="Std of the position noise [m].")
    velocity_noise_std: float = Field(0.0, ge=0, description="Std of the velocity noise [m/s].")


def _build(
    sec: RelativeStateSection, ctx: BuildContext
) -> RelativeStateSensors | ExactRelativeStateSensors:
    """The sensors of a validated ``[sensors] type = "relative-state"`` section."""
    if sec.position_noise_std == 0 and sec.velocity_noise_std == 0:
        return ExactRelativeStateSensors(count=ctx.count)
    return RelativeStateSensors(
        count=ctx.count, **section_floats(sec, "position_noise_std", "velocity_noise_std")
    )


register(
    "sensors",
    "relative-state",
    RelativeStateSection,
    _build,
    "relative position and velocity with Gaussian noise held over each step",
)
