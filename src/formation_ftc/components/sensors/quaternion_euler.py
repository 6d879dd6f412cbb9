"""Sensors ``quaternion-euler``: a quaternion rigid body's attitude reported as 3-2-1 Euler angles.

A law written in Euler angles (an Euler-Lagrange attitude law such as
:class:`~formation_ftc.components.controllers.networked_el_hinf.NetworkedElHinfController`) reads
``{"q": (N, 3) [theta, phi, psi], "w": (N, 3) body rates}``; a quaternion plant
(:class:`~formation_ftc.components.plants.quaternion_rigid_body.QuaternionRigidBodyPlant`) has the
state ``{"omega": (N, 3), "q": (N, 4)}``. These sensors convert (exactly, no noise)::

    C = rotation_matrix(p / |p|)                      body -> reference
    theta = atan2(-C31, hypot(C32, C33)),  phi = atan2(C32, C33),  psi = atan2(C21, C11)

i.e. ``C = Rz(psi) Ry(theta) Rx(phi)`` (Z-Y-X / 3-2-1 sequence, see
:mod:`formation_ftc.core.euler_quaternion`), and pass the body rates ``omega`` [rad/s] through; the
law forms the Euler-angle rates ``q_dot = R_bar(q) omega`` itself. Limits: singular at
theta = +-90 deg (gimbal lock); phi and psi are principal values in (-pi, pi], so an attitude that
crosses +-180 deg in roll or yaw jumps by 2 pi in the measurement (the sensors keep no state to unwrap).

Needs the capability ``quaternion-attitude-state`` (a quaternion plant) and provides
``euler-angle-measurement``.
"""

from __future__ import annotations

from formation_ftc.components._registry import BuildContext, register
from formation_ftc.config.base import StrictModel
from formation_ftc.core.euler_quaternion import euler_zyx_from_quaternion
from formation_ftc.sim.components import SensorInputs, Sensors, component, static

__all__ = ["QuaternionToEulerSensors", "QuaternionEulerSection"]


@component
class QuaternionToEulerSensors(Sensors):
    """Exact attitude measurement in 3-2-1 Euler angles from a quaternion plant state (module docstring).

    Static: ``count`` (number of spacecraft). Measurement ``{"q": [theta, phi, psi] [rad], "w": omega
    [rad/s]}`` (the form of the Euler-angle attitude plant's state).
    """

    count: int = static()

    def measure(self, t, x, inputs: SensorInputs):
        return {"q": euler_zyx_from_quaternion(x["q"]), "w": x["omega"]}

    def needs(self) -> dict[str, str]:
        return {"quaternion-attitude-state": "convert its quaternion to 3-2-1 Euler angles"}

    def provides(self) -> frozenset[str]:
        return frozenset({"euler-angle-measurement"})


class QuaternionEulerSection(StrictModel):
    """Exact measurement; no fields."""


def _build(sec: QuaternionEulerSection, ctx: BuildContext) -> QuaternionToEulerSensors:
    """The sensors of a ``[sensors] type = "quaternion-euler"`` section."""
    return QuaternionToEulerSensors(count=ctx.count)


register(
    "sensors",
    "quaternion-euler",
    QuaternionEulerSection,
    _build,
    "attitude as 3-2-1 Euler angles [theta, phi, psi] and body rates, from a quaternion plant",
)
