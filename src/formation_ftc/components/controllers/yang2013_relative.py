"""Controller ``yang2013-relative``: Yang2013's law (12) (``yang2013-translational``) made relative to
the spacecraft each one references over the (delayed) network, instead of its absolute slot.

Every spacecraft j transmits its formation error (the measured relative state minus its own desired
state, both in the plant's frame)::

    eps_j = [p_j - p^d_j(t),  v_j - v^d_j(t)]                      [m, m/s]

and spacecraft i receives, over the network's weighted graph and with its delays T_ij(t), the weighted
mean of the errors of the spacecraft it references::

    eps_bar_i = sum_j c_ij eps_j(t - T_ij(t)) / sum_j c_ij      (0 when i references nobody)

The wrapped law then regulates the error relative to them: it is evaluated on the shifted measurement
``y_i - beta_i eps_bar_i``, so a law that forms ``e_R = p^d - p`` (e.g. Yang2013 eq. (12)) regulates
``p^d_i - p_i + beta_i eps_bar_i``: with ``beta_i = 1`` spacecraft i keeps its desired offset relative
to the referenced spacecraft's (delayed) actual position (Yang2013's followers keep their position
relative to the main spacecraft), with ``beta_i = 0`` it tracks its own slot and ignores what it
receives (Yang2013's main spacecraft). With an instantaneous network (or zero delays) and every
``beta_i = 0`` the wrapper is the wrapped law exactly. The loop needs a ``[network]`` (the capability
``inter-spacecraft-messages``).
"""

from __future__ import annotations

from typing import Any, ClassVar

import jax
import jax.numpy as jnp
from pydantic import Field, field_validator

from formation_ftc.components._registry import BuildContext, per_spacecraft, register
from formation_ftc.components.controllers._yang2013 import translational_law
from formation_ftc.components.controllers.yang2013_translational import Yang2013TranslationalSection
from formation_ftc.sim.components import (
    CompositionError,
    Controller,
    FlightInputs,
    Signal,
    component,
)
from formation_ftc.sim.contract import VEC, as_float

__all__ = ["NeighbourRelativeController", "Yang2013RelativeSection"]


@component
class NeighbourRelativeController(Controller):
    """``law`` (a continuous force law on the measured (N, 6) relative state [p, v] [m, m/s] with a
    desired position, :meth:`~formation_ftc.sim.components.Controller.desired_position_at`, and no
    messages of its own) made relative to the referenced spacecraft; ``coupling`` beta_i (N,) [-]."""

    law: Controller
    coupling: Any  # (N,) beta_i [-]
    uses_messages: ClassVar[bool] = True

    def __post_init__(self) -> None:
        law = self.law
        if not isinstance(law, Controller):
            return  # pytree reconstruction with placeholders
        name = type(law).__name__
        if law.quantity != "force":
            raise CompositionError(
                f"NeighbourRelativeController wraps a force law; {name} commands a {law.quantity}"
            )
        if law.sampled or getattr(law, "uses_messages", False):
            raise CompositionError(
                f"NeighbourRelativeController wraps a continuous law without messages; "
                f"{name} is sampled or exchanges messages itself"
            )
        if type(law).desired_position_at is Controller.desired_position_at:
            raise CompositionError(
                f"NeighbourRelativeController needs a law with a desired position; {name} has none"
            )

    @property
    def count(self) -> int:
        return int(self.law.count)  # type: ignore[attr-defined]  # every translational law has a count

    def initial_state(self):
        return self.law.initial_state()

    def exogenous(self, t):
        def p_d(tt):
            return self.law.desired_position_at(self.law.exogenous(tt))

        return {"law": self.law.exogenous(t), "v": jax.jacfwd(p_d)(t)}  # v^d = dp^d/dt [m/s]

    def desired_position_at(self, exogenous):
        return self.law.desired_position_at(exogenous["law"])

    def message(self, t, inputs: FlightInputs):
        exo = inputs.exogenous
        p_d = self.law.desired_position_at(exo["law"])
        assert p_d is not None  # checked in __post_init__
        desired = jnp.concatenate([p_d, exo["v"]], axis=-1)
        return inputs.measurement - desired  # eps_j (N, 6) [m, m/s]

    def referenced_error(self, received) -> jax.Array:
        """eps_bar_i (N, 6) [m, m/s]: weighted mean of the received formation errors (0 without links)."""
        w = received["in_weight"]
        has = (w > 0)[:, None]
        return jnp.where(has, received["weighted_sum"] / jnp.where(has, w[:, None], 1.0), 0.0)

    def output(self, t, state, inputs: FlightInputs):
        eps_bar = self.referenced_error(inputs.received)
        shifted = inputs.measurement - self.coupling[:, None] * eps_bar
        law_exo = inputs.exogenous["law"]
        law_inputs = inputs._replace(measurement=shifted, received=None, exogenous=law_exo)
        u, d, out = self.law.output(t, state, law_inputs)
        out = dict(out)
        # what the law regulates: own formation error minus beta_i times the referenced one [m]
        out["relative_formation_error"] = (
            inputs.measurement[:, 0:3]
            - self.desired_position_at(inputs.exogenous)
            - self.coupling[:, None] * eps_bar[:, 0:3]
        )
        out["referenced_formation_error"] = eps_bar[:, 0:3]
        return u, d, out

    def signals(self):
        return tuple(self.law.signals()) + (
            Signal(
                "relative_formation_error",
                VEC,
                "m",
                "measured formation error minus coupling times the referenced spacecraft's received one",
                "LVLH",
            ),
            Signal(
                "referenced_formation_error",
                VEC,
                "m",
                "weighted mean of the received (delayed) formation errors of the referenced spacecraft",
                "LVLH",
            ),
        )

    def coords(self):
        return self.law.coords()

    def needs(self) -> dict[str, str]:
        return {
            "inter-spacecraft-messages": "receive the formation errors of the spacecraft it references"
        }


class Yang2013RelativeSection(Yang2013TranslationalSection):
    """Yang2013 eq. (12) keeping each spacecraft's offset relative to the (delayed) formation errors
    received from the spacecraft it references."""

    coupling: float | list[float] = Field(
        1.0,
        description="beta_i [-] in [0, 1] (one or per spacecraft): weight of the referenced spacecraft's "
        "received formation error; 1 keeps the offset relative to them, 0 tracks the own slot.",
    )

    @field_validator("coupling")
    @classmethod
    def _coupling(cls, value):
        values = value if isinstance(value, list) else [value]
        if any(not (0.0 <= v <= 1.0) for v in values):
            raise ValueError(f"every beta_i must lie in [0, 1], got {values}")
        return value


def _build(sec: Yang2013RelativeSection, ctx: BuildContext) -> NeighbourRelativeController:
    """The controller of a validated ``[controller] type = "yang2013-relative"`` section."""
    return NeighbourRelativeController(
        law=translational_law(ctx, sec),
        coupling=as_float(per_spacecraft(sec.coupling, ctx.count, "controller.coupling")),
    )


register(
    "controller",
    "yang2013-relative",
    Yang2013RelativeSection,
    _build,
    "Yang2013 law (12) keeping each spacecraft's offset relative to the (delayed) formation "
    "errors received from the spacecraft it references",
)
