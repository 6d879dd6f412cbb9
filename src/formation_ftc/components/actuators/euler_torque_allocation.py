"""Realise a generalised (Euler-angle) torque as the body torque of a quaternion rigid body.

An Euler-Lagrange attitude law in the 3-2-1 Euler angles ``q = [theta, phi, psi]`` commands the
generalised torque ``tau_gen`` [N m] conjugate to ``q``; a quaternion rigid body
(:class:`~formation_ftc.components.plants.quaternion_rigid_body.QuaternionRigidBodyPlant`) is driven by
the body torque. With ``omega = E(q) q_dot`` (``E = R_bar^{-1}``, see
:mod:`formation_ftc.core.euler_quaternion`) equal power ``tau_body . omega = tau_gen . q_dot`` gives::

    tau_body = E(q)^{-T} (tau_gen + u_bar) = R_bar(q)^T (tau_gen + u_bar)

where ``u_bar`` is what the wrapped actuator chain adds in the law's channels (e.g. the additive faults
of :class:`~formation_ftc.components.actuators.additive_faults.HeldAdditiveFaultActuator`, Mehrabian
(2)). The map uses the true attitude of the plant state at each RK stage (truth side), so
the body torque is exactly the one the Euler-angle plant applies for the same generalised torque: the
allocation stands for an on-board conversion with perfect attitude knowledge (the composition that
uses it measures with the exact
:class:`~formation_ftc.components.sensors.quaternion_euler.QuaternionToEulerSensors`). Singular at
pitch theta = +-90 deg (R_bar has 1/cos(theta)).
"""

from __future__ import annotations

import dataclasses

from formation_ftc.core.euler_quaternion import (
    body_torque_from_generalised,
    euler_zyx_from_quaternion,
)
from formation_ftc.sim.components import Actuator, ActuatorInputs, IdealActuator, Signal, component

__all__ = ["EulerTorqueAllocation"]

VEC = ("spacecraft", "axis")


@component
class EulerTorqueAllocation(Actuator):
    """``applied = R_bar(q)^T inner.apply(command)`` [N m, body axes] with q the true 3-2-1 Euler
    angles of the plant's quaternion (module docstring). ``inner`` is the actuator chain acting in the
    law's generalised channels (default: ideal). Records the generalised torque after ``inner``
    (``generalised_applied``) and the attitude used by the map (``attitude``, [theta, phi, psi])."""

    quantity = "torque"

    inner: Actuator = dataclasses.field(default_factory=IdealActuator)

    @property
    def holds_exogenous(self) -> bool:  # type: ignore[override]
        return self.inner.holds_exogenous

    @property
    def count(self) -> int | None:
        return getattr(self.inner, "count", None)

    def exogenous(self, t):
        return self.inner.exogenous(t)

    def initial_state(self):
        return self.inner.initial_state()

    def _generalised(self, t, command, inputs: ActuatorInputs):
        return self.inner.apply(t, command, inputs)

    def apply(self, t, command, inputs: ActuatorInputs):
        q = euler_zyx_from_quaternion(inputs.plant_state["q"])
        return body_torque_from_generalised(
            q, self._generalised(t, command, inputs)
        )  # tau_b = R_bar^T tau_gen

    def update(self, t, state, command, inputs: ActuatorInputs):
        return self.inner.update(t, state, command, inputs)

    def signals(self):
        return tuple(self.inner.signals()) + (
            Signal(
                "generalised_applied",
                VEC,
                "N m",
                "applied generalised torque conjugate to [theta, phi, psi] (command + faults)",
            ),
            Signal(
                "attitude",
                VEC,
                "rad",
                "true Euler angles [theta, phi, psi] (pitch, roll, yaw)",
                "body to reference Z-Y-X",
            ),
        )

    def coords(self):
        return self.inner.coords()

    def outputs(self, t, command, inputs: ActuatorInputs):
        out = dict(self.inner.outputs(t, command, inputs))
        out["generalised_applied"] = self._generalised(t, command, inputs)
        out["attitude"] = euler_zyx_from_quaternion(inputs.plant_state["q"])
        return out
