"""Actuator ``euler-torque-allocation``: a generalised (Euler-angle) torque, plus additive faults in
the law's channels, realised as the body torque of a quaternion rigid body.

An Euler-Lagrange attitude law in the 3-2-1 Euler angles ``q = [theta, phi, psi]`` commands the
generalised torque ``tau_gen`` [N m] conjugate to ``q``; a quaternion rigid body
(:class:`~formation_ftc.components.plants.quaternion_rigid_body.QuaternionRigidBodyPlant`) is driven by
the body torque. With ``omega = E(q) q_dot`` (``E = R_bar^{-1}``, see
:mod:`formation_ftc.core.euler_quaternion`) equal power ``tau_body . omega = tau_gen . q_dot`` gives::

    tau_body = E(q)^{-T} (tau_gen + u_bar) = R_bar(q)^T (tau_gen + u_bar)

where ``u_bar`` is what the wrapped actuator chain adds in the law's channels: here the additive
faults of :class:`HeldAdditiveFaultActuator` (Mehrabian (2)). The map uses the true attitude of the
plant state at each RK stage (truth side), so the body torque is exactly the one the Euler-angle plant
applies for the same generalised torque: the allocation stands for an on-board conversion with perfect
attitude knowledge (the composition that uses it measures with the exact
:class:`~formation_ftc.components.sensors.quaternion_euler.QuaternionToEulerSensors`). Singular at
pitch theta = +-90 deg (R_bar has 1/cos(theta)).

On a plant driven by the generalised torque itself (``euler-angle-attitude``: the capability
``euler-angle-attitude-state``) the faults are added to it without a mapping. Capabilities: the
allocation needs ``quaternion-attitude-state`` and provides ``generalised-torque-actuation``; with
faults the actuator provides ``scripted-actuator-faults`` (read by the ``scripted-fdi`` estimator).
"""

from __future__ import annotations

import dataclasses
from typing import Any, NamedTuple

import jax.numpy as jnp
import numpy as np
from pydantic import Field, model_validator

from formation_ftc.components._pass_through import PassThrough
from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.config.base import ExprText, StrictModel
from formation_ftc.core.euler_quaternion import (
    body_torque_from_generalised,
    euler_zyx_from_quaternion,
)
from formation_ftc.core.fault_profiles import windowed_additive_faults
from formation_ftc.sim.components import (
    Actuator,
    ActuatorInputs,
    IdealActuator,
    Signal,
    StepContext,
    component,
    static,
)
from formation_ftc.sim.contract import VEC, as_float

__all__ = [
    "EulerTorqueAllocation",
    "HeldAdditiveFaultActuator",
    "EulerAllocationSection",
    "FaultEntry",
    "FaultProfile",
]


@component
class HeldAdditiveFaultActuator(Actuator):
    """Additive actuator faults on windows of the step grid, sampled at the step start and held::

        applied_j = u_j + u_bar_j(t_k)                                     (Mehrabian (2))

    Every fault acts in one channel of one spacecraft with a profile written as an expression in t [s]
    and i (the 1-based spacecraft number), between a start and an end time snapped to the step grid
    (both inclusive), from :func:`~formation_ftc.core.fault_profiles.windowed_additive_faults`; the
    profile is evaluated at t_k and held over the step (truth side). Leaves: ``windows`` (n_faults, 2)
    [s]. Static: fault expressions, 0-based spacecraft and channels. The step grid is the loop's (its
    step context), not a copy of its own."""

    quantity = "torque"
    holds_exogenous = True

    count: int = static()
    windows: Any = None
    torques: tuple[str, ...] = static(default=())
    spacecraft: tuple[int, ...] = static(default=())
    channels: tuple[int, ...] = static(default=())
    n_channels: int = static(default=3)

    def held_exogenous(self, step: StepContext):
        if not self.torques:
            return {"fault": jnp.zeros((self.count, self.n_channels))}
        return {
            "fault": windowed_additive_faults(
                step.k,
                step.dt,
                self.windows,
                self.torques,
                self.spacecraft,
                self.channels,
                self.count,
                self.n_channels,
            )
        }

    def apply(self, t, command, inputs: ActuatorInputs):
        return command + inputs.exogenous["fault"]  # (2)

    def signals(self):
        return (Signal("fault", VEC, "N m", "true additive fault u_bar (2)"),)

    def outputs(self, t, command, inputs: ActuatorInputs):
        return {"fault": inputs.exogenous["fault"]}

    def provides(self) -> frozenset[str]:
        return frozenset({"scripted-actuator-faults"} if self.torques else ())


@component
class EulerTorqueAllocation(PassThrough, Actuator):  # type: ignore[override]  # a property holds_exogenous
    """``applied = R_bar(q)^T inner.apply(command)`` [N m, body axes] with q the true 3-2-1 Euler
    angles of the plant's quaternion (module docstring). ``inner`` is the actuator chain acting in the
    law's generalised channels (default: ideal). Records the generalised torque after ``inner``
    (``generalised_applied``) and the attitude used by the map (``attitude``, [theta, phi, psi])."""

    quantity = "torque"

    inner: Actuator = dataclasses.field(default_factory=IdealActuator)

    def initial_state(self):
        return self.inner.initial_state()

    def _generalised(self, t, command, inputs: ActuatorInputs):
        return self.inner.apply(t, command, inputs)

    def apply(self, t, command, inputs: ActuatorInputs):
        q = euler_zyx_from_quaternion(inputs.plant_state["q"])
        # tau_b = R_bar^T tau_gen
        return body_torque_from_generalised(q, self._generalised(t, command, inputs))

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

    def outputs(self, t, command, inputs: ActuatorInputs):
        out = dict(self.inner.outputs(t, command, inputs))
        out["generalised_applied"] = self._generalised(t, command, inputs)
        out["attitude"] = euler_zyx_from_quaternion(inputs.plant_state["q"])
        return out

    def needs(self) -> dict[str, str]:
        return {
            "quaternion-attitude-state": "map the generalised torque to a body torque with its "
            "quaternion",
            **self.inner.needs(),
        }

    def provides(self) -> frozenset[str]:
        return frozenset({"generalised-torque-actuation"}) | self.inner.provides()


class FaultEntry(StrictModel):
    spacecraft: int = Field(ge=1, description="Faulty spacecraft (1-based) [-].")
    channel: int = Field(
        ge=1, le=3, description="Faulty generalised channel 1 = pitch, 2 = roll, 3 = yaw [-]."
    )
    torque: ExprText = Field(
        description="Additive fault u_bar(t) while active, expression in t [s] [N m]."
    )
    start: float = Field(
        ge=0.0, description="Fault start (inclusive, snapped to the step grid) [s]."
    )
    end: float = Field(description="Fault end (inclusive, snapped to the step grid) [s].")

    @model_validator(mode="after")
    def _order(self):
        if not self.end >= self.start:
            raise ValueError(f"end = {self.end} s must be >= start = {self.start} s")
        return self


class FaultProfile(NamedTuple):
    """The faults of a section as the components take them (0-based spacecraft and channels)."""

    torques: tuple[str, ...]  # u_bar(t) expressions [N m]
    spacecraft: tuple[int, ...]
    channels: tuple[int, ...]
    windows: np.ndarray  # (n_faults, 2) [start, end] [s]
    mask: np.ndarray  # (N, 3) 1 where a fault acts [-]
    onset: float  # earliest start [s] (0 without faults)


class EulerAllocationSection(StrictModel):
    """tau_body = R_bar(q)^T (tau_gen + u_bar), u_bar the additive faults held over each step (on the
    Euler-angle plant, whose input is the generalised torque: tau_gen + u_bar, Mehrabian (2))."""

    faults: list[FaultEntry] = builder_input(
        default_factory=list, description="Additive faults in the law's generalised channels [N m]."
    )

    def fault_profile(self, count: int) -> FaultProfile:
        """The faults of ``count`` spacecraft (also what the ``scripted-fdi`` estimator reports).

        Parameters
        ----------
        count : int
            Number of spacecraft N of the plant.

        Returns
        -------
        FaultProfile
            Expressions, 0-based spacecraft and channels, windows, mask and onset.

        Raises
        ------
        ValueError
            A fault of a spacecraft the plant does not have (naming ``actuator.faults[k]``).
        """
        mask = np.zeros((count, 3))
        for k, f in enumerate(self.faults):
            if f.spacecraft > count:
                raise ValueError(
                    f"actuator.faults[{k}].spacecraft = {f.spacecraft}: the plant has {count} "
                    "spacecraft"
                )
            mask[f.spacecraft - 1, f.channel - 1] = 1.0
        return FaultProfile(
            torques=tuple(str(f.torque) for f in self.faults),
            spacecraft=tuple(f.spacecraft - 1 for f in self.faults),
            channels=tuple(f.channel - 1 for f in self.faults),
            windows=np.array([(f.start, f.end) for f in self.faults], dtype=float).reshape(-1, 2),
            mask=mask,
            onset=min((f.start for f in self.faults), default=0.0),
        )


def _build(sec: EulerAllocationSection, ctx: BuildContext) -> Actuator:
    """The actuator of a validated ``[actuator] type = "euler-torque-allocation"`` section: on a plant
    driven by the generalised torque the held faults alone, else the allocation around them."""
    profile = sec.fault_profile(ctx.count)
    held = HeldAdditiveFaultActuator(
        count=ctx.count,
        windows=as_float(profile.windows),
        torques=profile.torques,
        spacecraft=profile.spacecraft,
        channels=profile.channels,
    )
    if "euler-angle-attitude-state" in ctx.plant.provides():  # driven by the generalised torque
        return held
    return EulerTorqueAllocation(inner=held if sec.faults else IdealActuator())


register(
    "actuator",
    "euler-torque-allocation",
    EulerAllocationSection,
    _build,
    "generalised (Euler-angle) torque + additive faults -> body torque R_bar(q)^T (...) "
    "(unmapped on the Euler-angle plant)",
)
