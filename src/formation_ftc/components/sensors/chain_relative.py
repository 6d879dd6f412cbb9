"""Sensors ``chain-relative``: relative position and velocity measurements on a chain of spacecraft
pairs (1, 2), ..., (N-1, N), with optional held Gaussian noise.

The chain outputs are read from the plant's sensed state: positions ``"r"`` and velocities ``"v"``
(N, axes) of a double-integrator plant (:class:`ChainRelativeSensors`), or the (N, 6) relative state
``"q"`` of the relative-motion plants (:class:`ChainRelativeStateSensors`). Needs the capabilities
``translational-state`` and ``spacecraft-pairs`` of the plant; provides ``chain-outputs`` (what the
``azizi2009-llfr`` law and the ``hierarchical`` supervisor read).
"""

from __future__ import annotations

from typing import Any

import jax
from pydantic import Field

from formation_ftc.components._registry import BuildContext, register
from formation_ftc.components._sections import section_floats
from formation_ftc.config.base import StrictModel
from formation_ftc.core.disturbances import gaussian_noise
from formation_ftc.core.polygon_formation import chain_difference
from formation_ftc.sim.components import SensorInputs, Sensors, component, static

__all__ = [
    "ChainRelativeSensors",
    "ChainRelativeStateSensors",
    "ChainRelativeSection",
    "chain_layout",
]


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

    def needs(self) -> dict[str, str]:
        return {
            "translational-state": "measure relative positions and velocities on the chain pairs",
            "spacecraft-pairs": "measure at least one chain pair",
        }

    def provides(self) -> frozenset[str]:
        return frozenset({"chain-outputs"})

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


@component
class ChainRelativeStateSensors(ChainRelativeSensors):  # type: ignore[misc]  # fields inherited as declared
    """:class:`ChainRelativeSensors` for plants whose state is the (N, 6) relative state ``"q"`` =
    [x, y, z, vx, vy, vz] [m, m/s] (Clohessy-Wiltshire, nonlinear relative motion in LVLH, ...)::

        y["position"] = rho_{i+1} - rho_i + n_r,   y["velocity"] = v_{i+1} - v_i + n_v     (N-1, axes)

    on the first ``n_axes`` axes of the plant's frame, with the same held Gaussian noise streams as
    the parent: the chain outputs are the inter-spacecraft vectors in the plant frame's axes (LVLH
    for the relative plants), independent of where the reference itself is.
    """

    def measure(self, t, x, inputs: SensorInputs):
        q = x["q"]
        na = self.n_axes
        y = {
            "position": chain_difference(q[:, :na]),
            "velocity": chain_difference(q[:, 3 : 3 + na]),
        }
        if inputs.noise is not None:
            y = {k: y[k] + inputs.noise[k] for k in y}
        return y


def chain_layout(ctx: BuildContext) -> tuple[str, int]:
    """How the chain outputs are read from what sensors see of the built plant: ``("q", 3)`` for the
    (N, 6) relative state, ``("rv", axes)`` for positions ``r`` and velocities ``v`` (N, axes), or
    ``("none", 3)`` for a plant with neither (a placeholder layout: the parts that read the chain
    need the plant's ``translational-state``, and validation refuses the loop).

    Parameters
    ----------
    ctx : BuildContext
        The build context (its built plant).

    Returns
    -------
    tuple of (str, int)
        The layout and the number of axes.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> ctx = SimpleNamespace(sensed_shapes=lambda: {"r": (4, 2), "v": (4, 2)})
    >>> chain_layout(ctx)
    ('rv', 2)
    """
    shapes = ctx.sensed_shapes() or {}
    if shapes.get("q", ())[-1:] == (6,):
        return "q", 3
    if "r" in shapes and "v" in shapes and shapes["r"]:
        return "rv", int(shapes["r"][-1])
    return "none", 3


class ChainRelativeSection(StrictModel):
    """Relative positions and velocities on the chain pairs (1, 2), ..., (N-1, N)."""

    position_noise_std: float = Field(
        0.0, ge=0, description="Std of the noise on x_{i+1} - x_i [m]."
    )
    velocity_noise_std: float = Field(
        0.0, ge=0, description="Std of the noise on v_{i+1} - v_i [m/s]."
    )


def _build(sec: ChainRelativeSection, ctx: BuildContext) -> ChainRelativeSensors:
    """The sensors of a validated ``[sensors] type = "chain-relative"`` section."""
    layout, axes = chain_layout(ctx)
    cls = ChainRelativeStateSensors if layout == "q" else ChainRelativeSensors
    noisy = sec.position_noise_std > 0 or sec.velocity_noise_std > 0
    return cls(
        count=ctx.count,
        n_axes=axes,
        **section_floats(sec, "position_noise_std", "velocity_noise_std"),
        noisy=noisy,
    )


register(
    "sensors",
    "chain-relative",
    ChainRelativeSection,
    _build,
    "relative position and velocity on the chain pairs (1,2), ..., (N-1,N), optional noise",
)
