"""Shared part of the plants whose state is the (N, 6) relative state ``q = [position, velocity]``."""

from __future__ import annotations

from typing import Any

import numpy as np

from formation_ftc.sim.components import Plant

__all__ = ["RelativeStatePlant"]


class RelativeStatePlant(Plant):
    """Plant with state ``{"q": (N, 6)}`` in LVLH [m, m/s]: position and velocity views and the
    commanded delta-v / control-effort usage integrals (subclasses give the rates); the subclasses'
    fields ``mass`` (N,) [kg] and ``initial_state_lvlh`` (N, 6) [m, m/s] give the count and the
    initial state."""

    mass: Any  # declared by the subclasses (dataclass fields there)

    @property
    def count(self) -> int:
        return int(np.shape(self.mass)[0])

    def initial_state(self):
        return {"q": self.initial_state_lvlh}

    def provides(self) -> frozenset[str]:
        caps = {"translational-state", "lvlh-relative-state"}
        caps |= {"stage-evaluation"} if self.integration == "rk4" else set()
        return super().provides() | caps | ({"spacecraft-pairs"} if self.count >= 2 else set())

    def position(self, x):
        return x["q"][:, :3]

    def velocity(self, x):
        return x["q"][:, 3:]

    def usage_names(self):
        return ("delta_v", "control_effort")
