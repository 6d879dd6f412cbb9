"""What the quaternion rigid-body plants share (``quaternion-rigid-body``, ``attitude-truth``): the
state layout ``{"omega": (N, 3), "q": (N, 4)}`` (:class:`RigidBodyTorquePlant`, which provides the
capability ``quaternion-attitude-state``) and the section fields of the initial attitude
(:class:`RigidBodyAttitudeSection`)."""

from __future__ import annotations

import functools
from typing import Annotated, Any

import numpy as np
from pydantic import AfterValidator, Field, model_validator

from formation_ftc.components._registry import builder_input
from formation_ftc.components._sections import (
    Inertia,
    Quat,
    Vec3,
    Vec3Expr,
    check_rows,
    check_unit_quaternions,
)
from formation_ftc.components.expressions import vector_expression
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import Plant

__all__ = ["RigidBodyTorquePlant", "RigidBodyAttitudeSection", "QUATERNION_COMPONENTS"]

#: names of the quaternion's components, vector part first
QUATERNION_COMPONENTS = ["q1", "q2", "q3", "q4"]


class RigidBodyTorquePlant(Plant):
    """Rigid bodies in the state ``{"omega": (N, 3), "q": (N, 4)}`` from the fields
    ``initial_body_rate``, ``initial_quaternion``, driven by a torque plus the disturbance torque
    expressions ``disturbance_torque`` iota(t) [N m] (the state layout both quaternion attitude plants
    share: the capability ``quaternion-attitude-state``)."""

    quantity = "torque"
    initial_body_rate: Any  # declared by the subclasses (dataclass fields there)

    @property
    def count(self) -> int:
        return int(np.shape(self.initial_body_rate)[0])

    def initial_state(self):
        return {"omega": self.initial_body_rate, "q": self.initial_quaternion}

    def angular_rate(self, x):
        return x["omega"]

    def exogenous(self, t):
        return {
            "iota": vector_expression(self.disturbance_torque, "disturbance.torque", t, self.count)
        }

    def coords(self):
        return {"quaternion_component": QUATERNION_COMPONENTS}

    def provides(self) -> frozenset[str]:
        return frozenset({"quaternion-attitude-state"})


# Build-time conversions of a section's initial attitude, each one compiled program: evaluated operation
# by operation they compiled about 50 small programs (1.4-1.5 s) the first time a process loaded such a
# scenario.
@functools.cache
def _jitted(name: str):
    """The jitted map ``name`` of :mod:`formation_ftc.core.euler_quaternion` (ZYX Euler <-> quaternion),
    compiled as the simulation programs are (:func:`formation_ftc.sim.runtime.xla.jit`) on first use (JAX
    is imported by builds only)."""
    from formation_ftc.core import euler_quaternion
    from formation_ftc.sim.runtime import xla

    return xla.jit(getattr(euler_quaternion, name))


class RigidBodyAttitudeSection(StrictModel):
    """Fields shared by the rigid-body attitude plants: principal inertia, initial attitude (Euler
    angles or quaternions), initial body rate and disturbance torque, with their checks."""

    inertia: Inertia = Field(
        description="Principal inertia diag(J) of every spacecraft [kg m^2], each > 0."
    )
    initial_attitude_deg: list[Vec3] | None = builder_input(
        None,
        description="Initial 3-2-1 Euler angles [theta (pitch), phi (roll), psi (yaw)] per spacecraft "
        "[deg] (converted to quaternions; give this or initial_quaternion).",
    )
    initial_quaternion: Annotated[list[Quat] | None, AfterValidator(check_unit_quaternions)] = (
        Field(
            None,
            description="Initial unit quaternion [q1, q2, q3, q4] (vector first) per spacecraft [-].",
        )
    )
    initial_body_rate: list[Vec3] | None = Field(
        None,
        description="Initial body angular velocity per spacecraft, body axes [rad/s] (default 0).",
    )
    disturbance_torque: Vec3Expr = Field(
        ("0", "0", "0"),
        description="Disturbance torque iota(t) in body axes, expressions in t [s], i [N m].",
    )

    @model_validator(mode="after")
    def _initial_attitude(self):
        if (self.initial_attitude_deg is None) == (self.initial_quaternion is None):
            raise ValueError(
                "give exactly one of initial_attitude_deg [deg] and initial_quaternion [-]"
            )
        n = self.count
        if n < 1:
            raise ValueError("initial_attitude_deg / initial_quaternion: at least one spacecraft")
        check_rows(self, ["initial_body_rate"], n)
        return self

    @property
    def count(self) -> int:
        """Number of spacecraft N [-]."""
        return len(self.initial_attitude_deg or self.initial_quaternion or [])

    def body_rates(self) -> np.ndarray:
        """(N, 3) initial body rates as given [rad/s] (default 0)."""
        if self.initial_body_rate is None:
            return np.zeros((self.count, 3))
        return np.asarray(self.initial_body_rate, float)

    def given_quaternions(self) -> np.ndarray:
        """(N, 4) initial unit quaternions as given (Euler angles converted, quaternions normalised)."""
        if self.initial_quaternion is not None:
            p = np.asarray(self.initial_quaternion, dtype=float)
            return p / np.linalg.norm(p, axis=-1, keepdims=True)
        return np.asarray(
            _jitted("quaternion_from_euler_zyx")(
                np.deg2rad(np.asarray(self.initial_attitude_deg, float))
            )
        )

    def quaternions(self) -> np.ndarray:
        """(N, 4) initial unit quaternions of the plant's state."""
        return self.given_quaternions()

    def euler_angles(self) -> np.ndarray:
        """(N, 3) initial 3-2-1 Euler angles [rad] of the plant's state."""
        return np.asarray(_jitted("euler_zyx_from_quaternion")(self.quaternions()))
