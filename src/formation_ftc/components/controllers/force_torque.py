"""A 6-DOF law made of a translational (force) law and an attitude (torque) law."""

from __future__ import annotations

import jax.numpy as jnp

from formation_ftc.sim.components import CompositionError, Controller, FlightInputs, component

__all__ = ["ForceTorqueController", "WRENCH_COMPONENTS"]

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
        if (
            f.sampled
            or t.sampled
            or getattr(f, "uses_messages", False)
            or getattr(t, "uses_messages", False)
        ):
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
        f, df, of = self.force_law.output(
            t,
            state["force"],
            inputs._replace(measurement=m["translation"], exogenous=inputs.exogenous["force"]),
        )
        tau, dt_, ot = self.torque_law.output(
            t,
            state["torque"],
            inputs._replace(
                measurement={"omega": m["omega"], "q": m["q"]}, exogenous=inputs.exogenous["torque"]
            ),
        )
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
