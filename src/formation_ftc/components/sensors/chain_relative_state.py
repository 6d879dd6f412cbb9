"""Chain relative measurements read from the (N, 6) relative state of a translational plant."""

from __future__ import annotations

from formation_ftc.components.sensors.chain_relative import ChainRelativeSensors
from formation_ftc.core.polygon_formation import chain_difference
from formation_ftc.sim.components import SensorInputs, component

__all__ = ["ChainRelativeStateSensors"]


@component
class ChainRelativeStateSensors(ChainRelativeSensors):  # type: ignore[misc]  # fields inherited as declared
    """:class:`~formation_ftc.components.sensors.chain_relative.ChainRelativeSensors` for plants whose
    state is the (N, 6) relative state ``"q"`` = [x, y, z, vx, vy, vz] [m, m/s] (Clohessy-Wiltshire,
    nonlinear relative motion in LVLH, ...)::

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
