"""Sensors: what the flight side may see of the truth."""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from formation_ftc.core.disturbances import gaussian_noise
from formation_ftc.sim.components import SensorInputs, Sensors, component, static

__all__ = ["RelativeStateSensors"]


@component
class RelativeStateSensors(Sensors):
    """Relative position and velocity of every spacecraft with additive Gaussian noise drawn once per
    step (held over the step): y = [q[:, :3] + n_p, q[:, 3:] + n_v] [m, m/s]. The plant state must
    hold the (N, 6) relative state under ``"q"``."""

    count: int = static()  # number of spacecraft
    position_noise_std: Any = 0.0  # [m]
    velocity_noise_std: Any = 0.0  # [m/s]

    def noise(self, key):
        n = self.count
        k_p, k_v = jax.random.split(key, 2)
        return jnp.concatenate(
            [
                gaussian_noise(k_p, (n, 3), self.position_noise_std),
                gaussian_noise(k_v, (n, 3), self.velocity_noise_std),
            ],
            axis=-1,
        )

    def measure(self, t, x, inputs: SensorInputs):
        return x["q"] + inputs.noise

    def provides(self) -> frozenset[str]:
        return frozenset({"relative-state-measurement"})
