"""Controller ``yang2013-force-torque``: Yang2013's laws (12) and (13) side by side, a wrench on the
error state of the switched formation (``switched-formation`` plant, ``tracking-error`` sensors).

The equations and the two laws are in :mod:`formation_ftc.components.controllers._yang2013`; the laws'
on-board mass and inertia are stated (``nominal_mass``, default 150 kg; ``nominal_inertia``, default
diag(25, 25, 25) kg m^2). Needs the measured error state (the capability ``error-state-measurement``);
provides the velocity gain K2 a ``velocity-gain-fault`` actuator corrupts (``velocity-gain-law``).
"""

from __future__ import annotations

import jax.numpy as jnp
from pydantic import Field, PositiveFloat

from formation_ftc.components._flight_defaults import NOMINAL_INERTIA, YANG2013_NOMINAL_MASS
from formation_ftc.components._registry import BuildContext, register
from formation_ftc.components.controllers._yang2013 import attitude_law, translational_law
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import CompositionError, Controller, FlightInputs, component

__all__ = ["ForceTorqueController", "WRENCH_COMPONENTS", "Yang2013ForceTorqueSection"]

WRENCH_COMPONENTS = ["f_x", "f_y", "f_z", "tau_x", "tau_y", "tau_z"]


@component
class ForceTorqueController(Controller):
    """Wrench command ``[f, tau]`` (N, 6) [N, N m] of a force law and a torque law evaluated side by side.

    The measurement must be ``{"translation": (N, 6), "omega": (N, 3), "q": (N, 4)}``: the force law
    receives the (N, 6) relative state, the torque law ``{"omega", "q"}``; each receives its own time
    signals. When the supervisor's decision carries a membership mask ``active`` (N,), spacecraft
    outside the formation get a zero command.
    """

    quantity = "wrench"

    force_law: Controller
    torque_law: Controller

    def __post_init__(self) -> None:
        f, t = self.force_law, self.torque_law
        if not isinstance(f, Controller) or not isinstance(t, Controller):
            return  # pytree reconstruction with placeholders
        if f.quantity != "force" or t.quantity != "torque":
            raise CompositionError(
                f"ForceTorqueController needs a force law and a torque law, got "
                f"{type(f).__name__} ({f.quantity}) and {type(t).__name__} ({t.quantity})"
            )
        if any(law.sampled or getattr(law, "uses_messages", False) for law in (f, t)):
            raise CompositionError(
                f"ForceTorqueController combines continuous laws without messages; "
                f"{type(f).__name__} / {type(t).__name__} are sampled or exchange messages"
            )

    @property
    def count(self) -> int:
        return self.force_law.count  # type: ignore[attr-defined]  # every force law declares count

    def initial_state(self):
        return {"force": self.force_law.initial_state(), "torque": self.torque_law.initial_state()}

    def exogenous(self, t):
        return {"force": self.force_law.exogenous(t), "torque": self.torque_law.exogenous(t)}

    def output(self, t, state, inputs: FlightInputs):
        m = inputs.measurement
        state = state or {"force": None, "torque": None}
        exo, attitude = inputs.exogenous, {"omega": m["omega"], "q": m["q"]}
        force_in = inputs._replace(measurement=m["translation"], exogenous=exo["force"])
        torque_in = inputs._replace(measurement=attitude, exogenous=exo["torque"])
        f, df, of = self.force_law.output(t, state["force"], force_in)
        tau, dt_, ot = self.torque_law.output(t, state["torque"], torque_in)
        u = jnp.concatenate([f, tau], axis=-1)
        active = getattr(inputs.decision, "active", None)
        if active is not None:
            u = u * active[:, None]
        return u, {"force": df, "torque": dt_}, {**of, **ot}

    def signals(self):
        return tuple(self.force_law.signals()) + tuple(self.torque_law.signals())

    def coords(self):
        return {
            **self.force_law.coords(),
            **self.torque_law.coords(),
            "wrench_component": WRENCH_COMPONENTS,
        }

    def needs(self) -> dict[str, str]:
        return {"error-state-measurement": "evaluate (12)-(13) on the measured error state"}

    def provides(self) -> frozenset[str]:
        return frozenset({"velocity-gain-law"})


PositiveVec3 = tuple[PositiveFloat, PositiveFloat, PositiveFloat]


class Yang2013ForceTorqueSection(StrictModel):
    """Gains of (12)-(13); positive (E001-01); the laws' stated on-board mass and inertia."""

    K1: float = Field(0.005, gt=0, description="Position gain offset K1 (e_R gain K1+1) [1/s^2].")
    K2: float = Field(0.01, gt=0, description="Velocity gain K2 [1/s].")
    K3: float = Field(0.2, gt=0, description="Angular-rate gain K3 [1/s].")
    K4: float = Field(1.0, gt=0, description="Quaternion-vector shaping gain K4 [1/s].")
    K5: float = Field(1.0, gt=0, description="Quaternion-scalar shaping gain K5 [1/s].")
    kappa: float = Field(1e-3, gt=0, description="Smoothing constant kappa of (13) [rad^2/s^2].")
    nominal_mass: float = Field(
        YANG2013_NOMINAL_MASS,
        gt=0,
        description="Mass M_i the translational law (12) knows on board [kg] (default 150 kg, a "
        "stated nominal value: never the plant's true mass). Also the mass of the faulty law's "
        "K2 -> K2f term.",
    )
    nominal_inertia: PositiveVec3 = Field(
        NOMINAL_INERTIA,
        description="Principal inertia diag(J_i) the attitude law (13) knows on board [kg m^2], each "
        "> 0 (default 25, 25, 25 kg m^2, a stated nominal value: never the plant's true inertia).",
    )


def _build(sec: Yang2013ForceTorqueSection, ctx: BuildContext) -> ForceTorqueController:
    """The controller of a validated ``[controller] type = "yang2013-force-torque"`` section."""
    return ForceTorqueController(
        force_law=translational_law(ctx, sec),  # eq. (12)
        torque_law=attitude_law(ctx, sec),  # (13)
    )


register(
    "controller",
    "yang2013-force-torque",
    Yang2013ForceTorqueSection,
    _build,
    "Yang2013 laws (12)-(13) side by side: wrench on the error state",
)
