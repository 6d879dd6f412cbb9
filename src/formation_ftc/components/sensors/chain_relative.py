"""Relative position and velocity measurements on a chain of spacecraft pairs."""

from __future__ import annotations

from typing import Any

import jax

from formation_ftc.core.disturbances import gaussian_noise
from formation_ftc.core.polygon_formation import chain_difference
from formation_ftc.sim.components import SensorInputs, Sensors, component, static

__all__ = ["ChainRelativeSensors"]


@component
class ChainRelativeSensors(Sensors):
    """Inter-satellite measurements on the chain pairs (1, 2), ..., (N-1, N)::

        y["position"] = x_{i+1} - x_i + n_r,   y["velocity"] = v_{i+1} - v_i + n_v      (N-1, axes)

    [m, m/s] with Gaussian noise drawn once per step and held (``noisy = False``: exact, no random
    draws). The step key is split as (position, velocity) streams. The plant state must hold the
    positions ``"r"`` and velocities ``"v"`` (N, axes).
    """

    count: int = static()
    n_axes: int = static()
    position_noise_std: Any = 0.0  # [m]
    velocity_noise_std: Any = 0.0  # [m/s]
    noisy: bool = static(default=False)

    splits_step_key = True

    def noise(self, key):
        if not self.noisy:
            return None
        k_r, k_v = jax.random.split(key)
        shape = (self.count - 1, self.n_axes)
        return {
            "position": gaussian_noise(k_r, shape, self.position_noise_std),
            "velocity": gaussian_noise(k_v, shape, self.velocity_noise_std),
        }

    def measure(self, t, x, inputs: SensorInputs):
        y = {"position": chain_difference(x["r"]), "velocity": chain_difference(x["v"])}
        if inputs.noise is not None:
            y = {k: y[k] + inputs.noise[k] for k in y}
        return y
