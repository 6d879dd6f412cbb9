"""Shared part of the point-mass plants whose state is, or is seen by sensors as, the (N, 6) LVLH
relative state ``q = [position, velocity]`` (``clohessy-wiltshire``, ``clohessy-wiltshire-zoh``,
``relative-lvlh``, ``orbital-truth``): the base class and the section fields of their spacecraft."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from pydantic import Field, model_validator

from formation_ftc.components._registry import builder_input
from formation_ftc.components._sections import Vec3, Vec3Expr, check_rows, initial_states
from formation_ftc.config.base import StrictModel
from formation_ftc.core.vector3 import norm3, sq_norm3
from formation_ftc.sim.components import Plant

__all__ = ["RelativeStatePlant", "PointMassUsage", "PointMassSection"]


class RelativeStatePlant(Plant):
    """Plant with state ``{"q": (N, 6)}`` in LVLH [m, m/s]: position and velocity views; the
    subclasses' field ``initial_state_lvlh`` (N, 6) [m, m/s] gives the count and the initial state."""

    initial_state_lvlh: Any  # declared by the subclasses (a dataclass field there)

    @property
    def count(self) -> int:
        return int(np.shape(self.initial_state_lvlh)[0])

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


class PointMassUsage:
    """Usage integrals of a plant with masses (listed before the plant base): the commanded delta-v
    int ||u_i|| / m_i dt [m/s] and control effort int ||u_i||^2 dt [N^2 s]; ``mass`` (N,) [kg]."""

    mass: Any  # declared by the plant (a dataclass field there)

    def usage_names(self):
        return ("delta_v", "control_effort")

    def usage_rates(self, t, x, command):
        return {"delta_v": norm3(command) / self.mass, "control_effort": sq_norm3(command)}


class PointMassSection(StrictModel):
    """N point-mass spacecraft: true masses, initial LVLH states (the builder stacks them into the
    plant's ``initial_state_lvlh``) and a disturbance force."""

    mass: list[float] = Field(description="True mass of each spacecraft [kg], > 0.")
    initial_position: list[Vec3] = builder_input(
        description="Initial LVLH position per spacecraft [m]."
    )
    initial_velocity: list[Vec3] | None = builder_input(
        None, description="Initial LVLH velocity per spacecraft [m/s] (default 0)."
    )
    disturbance_force: Vec3Expr = Field(
        ("0", "0", "0"), description="External force per axis, expressions in t [s], i [N]."
    )

    @model_validator(mode="after")
    def _sizes(self):
        n = len(self.mass)
        if n < 1 or any(not (m > 0 and math.isfinite(m)) for m in self.mass):
            raise ValueError("mass: at least one spacecraft, every mass finite and > 0 kg")
        check_rows(self, ["initial_position", "initial_velocity"], n)
        return self

    @property
    def count(self) -> int:
        """Number of spacecraft N [-]."""
        return len(self.mass)

    def q0(self) -> np.ndarray:
        """The (N, 6) initial relative states [m, m/s]."""
        return initial_states(self.initial_position, self.initial_velocity)
