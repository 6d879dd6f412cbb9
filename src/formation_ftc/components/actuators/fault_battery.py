"""Actuator ``fault-battery``: per-axis saturation and one thruster-level fault of a chosen kind.

``[actuator] type = "fault-battery"``::

    kind = "loss_of_effectiveness"   # none, loss_of_effectiveness, bias, stuck, outage, intermittent, degrading
    spacecraft = 2                   # faulty spacecraft, 1-based
    axis = 0                         # faulty axis 0, 1, 2
    onset = 1000.0                   # [s]
    effectiveness = 0.5              # loss_of_effectiveness [-]
    bias = 0.0                       # bias [N, or N m on a torque plant]
    period = 60.0                    # intermittent [s]
    duty = 0.5                       # intermittent on-fraction [-]
    rate = 0.0                       # degrading [1/s]
    min_effectiveness = 0.0          # degrading floor [-]
    saturation = 1.0                 # per-axis limit [N or N m]: one number or one per spacecraft; omit: none
    euler_allocation = false         # the law commands a 3-2-1 Euler-angle generalised torque

Every quantity that distinguishes one fault case from another -- the kind, the faulty channel
(spacecraft, axis), the onset, the magnitudes and the saturation limit -- is a numeric array leaf, so
the cases of a battery differ only in their leaves and share one compiled program (a campaign or a
league ``vmap``-s over them). Each kind's effect is computed with masks; no Python branch depends on a
leaf. The only structural choices are the spacecraft count, whether a generalised Euler-angle torque is
first mapped to a body torque (``euler_allocation``) and the units of the output.

For a command ``u`` (N, 3) [N or N m], per spacecraft i and axis k::

    u_sat = clip(u, -limit_i, limit_i)                                   (per-axis saturation)
    applied = g(t) u_sat + b(t)   on the faulty channel (i*, k*) for t >= onset; u_sat elsewhere

with, by kind (``FAULT_KINDS``, the ``fault_kind`` leaf is the index; ``tau = t - onset``):

==========================  ===============================================================
none                        g = 1, b = 0
loss_of_effectiveness       g = effectiveness, b = 0
bias                        g = 1, b = bias
stuck                       g = 0, b = u_sat of the channel at onset (held in the actuator state)
outage ("float")            g = 0, b = 0
intermittent                g = 1 during the first duty * period of each period, 0 after it
degrading                   g = max(min_effectiveness, 1 - rate tau)
==========================  ===============================================================

Times are compared as the loop's truth-side time signals are (an onset on the step grid acts from that
step on). *Stuck*: the frozen value is the saturated command of the faulty channel at the first step
time ``t_k >= onset`` (stored by :meth:`FaultBatteryActuator.update` after that step); during that
first step the channel passes its current saturated command (exactly the frozen value for a law sampled
once per step).

Provides ``true-actuator-fault`` (the ``fault_active`` and ``fault_channel`` records the ``fdi-scores``
evaluation compares a fault detector with). They start when the actuator first departs from nominal,
which is the onset for every kind but *intermittent*: its first ``duty * period`` after the onset is
an on phase (the thruster works), so its fault starts at the first off phase (never for ``duty = 1``).
A detection delay is then the time the thruster was not nominal before the alarm, and an alarm in that
first on phase is a false alarm. With ``euler_allocation`` it needs the plant's
``quaternion-attitude-state`` and provides ``generalised-torque-actuation``.
"""

from __future__ import annotations

from typing import Annotated, Any

import jax.numpy as jnp
import numpy as np
from pydantic import Field, field_validator

from formation_ftc.components._registry import BuildContext, builder_input, per_spacecraft, register
from formation_ftc.components._sections import positive_values, section_floats
from formation_ftc.components.actuators.euler_torque_allocation import EulerTorqueAllocation
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import Actuator, ActuatorInputs, Signal, component, static
from formation_ftc.sim.contract import VEC, as_float

__all__ = ["FaultBatteryActuator", "FaultBatterySection", "FAULT_KINDS", "fault_kind_code"]

#: fault kind names; a kind's code (the ``fault_kind`` leaf) is its index in this tuple
FAULT_KINDS: tuple[str, ...] = (
    "none",
    "loss_of_effectiveness",
    "bias",
    "stuck",
    "outage",
    "intermittent",
    "degrading",
)

_CODE = {name: code for code, name in enumerate(FAULT_KINDS)}


def fault_kind_code(name: str) -> int:
    """The numeric code of the fault kind ``name`` (raises ``ValueError`` naming the allowed names).

    Parameters
    ----------
    name : str
        A name of :data:`FAULT_KINDS`.

    Returns
    -------
    int
        Its index in :data:`FAULT_KINDS` (the ``fault_kind`` leaf) [-].

    Raises
    ------
    ValueError
        Unknown name.

    Examples
    --------
    >>> from formation_ftc.components.actuators.fault_battery import fault_kind_code
    >>> fault_kind_code("none"), fault_kind_code("stuck")
    (0, 3)
    >>> fault_kind_code("jammed")
    Traceback (most recent call last):
    ...
    ValueError: unknown fault kind 'jammed' (allowed: none, loss_of_effectiveness, bias, stuck, outage, intermittent, degrading)
    """
    try:
        return _CODE[name]
    except KeyError:
        raise ValueError(
            f"unknown fault kind {name!r} (allowed: {', '.join(FAULT_KINDS)})"
        ) from None


@component
class FaultBatteryActuator(Actuator):
    """Per-axis saturation then one fault on channel (spacecraft, axis) of kind ``fault_kind`` (module docstring).

    Leaves: ``saturation`` scalar or (N,) per-axis limit [N or N m] (inf: unsaturated); ``fault_kind`` code in
    :data:`FAULT_KINDS` [-]; ``spacecraft`` 1-based [-]; ``axis`` 0, 1 or 2 [-]; ``onset`` [s];
    ``effectiveness`` [-]; ``bias`` [N or N m]; ``period`` [s] and ``duty`` [-] (intermittent);
    ``rate`` [1/s] and ``min_effectiveness`` [-] (degrading). Static: ``count`` N, ``euler_allocation``
    (the command is a generalised 3-2-1 Euler-angle torque, mapped to the body torque as
    :class:`~formation_ftc.components.actuators.euler_torque_allocation.EulerTorqueAllocation` does
    before saturation and fault act in body axes), ``units`` of the command.

    Records ``effectiveness`` (N, 3) the true gain g [-] (0 on a stuck or outage channel),
    ``saturated`` (N,) 1 when any axis of the spacecraft's command is at or beyond its limit,
    ``fault_active`` () 1 from the fault's first departure from nominal on (the onset; an intermittent
    fault's first off phase; 0 throughout for kind none).
    """

    count: int = static()
    saturation: Any = float("inf")  # () or (N,) [N or N m]
    fault_kind: Any = 0.0  # code, index in FAULT_KINDS [-]
    spacecraft: Any = 1.0  # faulty spacecraft, 1-based [-]
    axis: Any = 0.0  # faulty axis 0..2 [-]
    onset: Any = 0.0  # [s]
    effectiveness: Any = 1.0  # loss_of_effectiveness gain [-]
    bias: Any = 0.0  # [N or N m]
    period: Any = 1.0  # intermittent period [s]
    duty: Any = 1.0  # intermittent on-fraction [-]
    rate: Any = 0.0  # degrading rate [1/s]
    min_effectiveness: Any = 0.0  # degrading floor [-]
    euler_allocation: bool = static(default=False)
    units: str = static(default="N")

    # ------------------------------------------------------------------ pieces
    def _is(self, name: str) -> jnp.ndarray:
        return jnp.asarray(self.fault_kind) == _CODE[name]

    def _channel(self) -> jnp.ndarray:
        """(N, 3) boolean mask of the faulty channel."""
        sc = jnp.arange(1, self.count + 1)[:, None] == jnp.asarray(self.spacecraft)
        ax = jnp.arange(3)[None, :] == jnp.asarray(self.axis)
        return sc & ax

    def _limit(self) -> jnp.ndarray:
        """(N, 1) per-axis limit [N or N m]."""
        limit = jnp.broadcast_to(jnp.asarray(self.saturation, dtype=jnp.float64), (self.count,))
        return limit[:, None]

    def needs(self) -> dict[str, str]:
        if not self.euler_allocation:
            return {}
        return {
            "quaternion-attitude-state": "map the generalised torque to a body torque with its "
            "quaternion (euler_allocation)"
        }

    def provides(self) -> frozenset[str]:
        euler = {"generalised-torque-actuation"} if self.euler_allocation else set()
        return frozenset({"true-actuator-fault"} | euler)

    def _body(self, t, command, inputs: ActuatorInputs):
        """The command in the actuator's axes (after the Euler-angle allocation when static-enabled)."""
        if self.euler_allocation:
            return EulerTorqueAllocation().apply(t, command, inputs)  # tau_b = R_bar(q)^T tau_gen
        return command

    def exogenous(self, t):
        tau = t - self.onset
        active = (tau >= 0.0) & ~self._is("none")
        phase = jnp.mod(jnp.maximum(tau, 0.0), self.period)
        on = phase < self.duty * self.period
        # the first departure from nominal: the onset, or an intermittent fault's first off phase
        first_off = jnp.where(
            self._is("intermittent"),
            jnp.where(self.duty < 1.0, self.duty * self.period, jnp.inf),
            0.0,
        )
        g = jnp.where(self._is("loss_of_effectiveness"), self.effectiveness, 1.0)
        g = jnp.where(self._is("stuck") | self._is("outage"), 0.0, g)
        g = jnp.where(self._is("intermittent"), jnp.where(on, 1.0, 0.0), g)
        g = jnp.where(
            self._is("degrading"), jnp.maximum(self.min_effectiveness, 1.0 - self.rate * tau), g
        )
        b = jnp.where(self._is("bias"), self.bias, 0.0)
        on_channel = self._channel() & active
        return {
            "gain": jnp.where(on_channel, g, 1.0),  # (N, 3)
            "bias": jnp.where(on_channel, b, 0.0),  # (N, 3)
            "stuck": on_channel & self._is("stuck"),  # (N, 3)
            "departed": active & (tau >= first_off),  # the fault in the scores (module docstring)
        }

    def initial_state(self):
        return {"value": jnp.zeros((self.count, 3)), "frozen": jnp.asarray(False)}

    def _saturated(self, u):
        return jnp.clip(u, -self._limit(), self._limit())

    # ------------------------------------------------------------------ the contract
    def apply(self, t, command, inputs: ActuatorInputs):
        u = self._saturated(self._body(t, command, inputs))
        exo = inputs.exogenous
        y = exo["gain"] * u + exo["bias"]
        state = inputs.state
        # a caller without the actuator state: the channel passes its saturated command
        if state is None:
            return jnp.where(exo["stuck"], u, y)
        return jnp.where(exo["stuck"], jnp.where(state["frozen"], state["value"], u), y)

    def update(self, t, state, command, inputs: ActuatorInputs):
        freeze = (t >= self.onset) & ~state["frozen"]
        u = self._saturated(self._body(t, command, inputs))
        return {"value": jnp.where(freeze, u, state["value"]), "frozen": state["frozen"] | freeze}

    def signals(self):
        return (
            Signal(
                "effectiveness",
                VEC,
                "1",
                "true actuator effectiveness g (after saturation; 0 on a stuck or outage channel)",
            ),
            Signal(
                "saturated",
                ("spacecraft",),
                "1",
                "1 when any axis command is at its saturation limit",
            ),
            Signal(
                "fault_active",
                (),
                "1",
                "1 from the fault's first departure from nominal on (the onset; for an intermittent "
                "fault its first off phase)",
            ),
            Signal(
                "fault_channel",
                VEC,
                "1",
                "1 on the faulty (spacecraft, axis) channel from the fault's first departure on",
            ),
        )

    def outputs(self, t, command, inputs: ActuatorInputs):
        u = self._body(t, command, inputs)
        at_limit = jnp.any(jnp.abs(u) >= self._limit(), axis=-1)
        exo = inputs.exogenous
        return {
            "effectiveness": exo["gain"],
            "saturated": jnp.where(at_limit, 1.0, 0.0),
            "fault_active": jnp.where(exo["departed"], 1.0, 0.0),
            "fault_channel": jnp.where(self._channel() & exo["departed"], 1.0, 0.0),
        }


class FaultBatterySection(StrictModel):
    """Per-axis saturation, then one fault of kind ``kind`` on channel (spacecraft, axis) from ``onset``."""

    kind: str = builder_input(
        "none",
        description=f"Fault kind: one of {', '.join(FAULT_KINDS)} (the component's fault_kind is its "
        "index).",
    )
    spacecraft: int = Field(1, ge=1, description="Faulty spacecraft (1-based) [-].")
    axis: int = Field(0, ge=0, le=2, description="Faulty axis 0, 1 or 2 [-].")
    onset: float = Field(
        0.0, ge=0.0, description="Fault onset (acts from the first step at or after it) [s]."
    )
    effectiveness: float = Field(
        1.0, ge=0.0, description="Gain of a loss_of_effectiveness fault [-]."
    )
    bias: float = Field(
        0.0, description="Additive output of a bias fault [N, or N m on a torque plant]."
    )
    period: float = Field(60.0, gt=0.0, description="Period of an intermittent fault [s].")
    duty: float = Field(
        0.5, ge=0.0, le=1.0, description="On-fraction of each intermittent period [-]."
    )
    rate: float = Field(
        0.0, ge=0.0, description="Effectiveness loss rate of a degrading fault [1/s]."
    )
    min_effectiveness: float = Field(
        0.0, ge=0.0, le=1.0, description="Floor of a degrading fault's effectiveness [-]."
    )
    saturation: Annotated[float | list[float] | None, positive_values("limit", " N or N m")] = (
        Field(
            None,
            description="Per-axis output limit [N or N m], one number or one per spacecraft (omit: unsaturated).",
        )
    )
    euler_allocation: bool = Field(
        False,
        description="Map a generalised 3-2-1 Euler-angle torque to the body "
        "torque first (quaternion plants).",
    )

    @field_validator("kind")
    @classmethod
    def _kind(cls, v: str) -> str:
        if v not in FAULT_KINDS:
            raise ValueError(
                f"kind = {v!r} is not a fault kind (allowed: {', '.join(FAULT_KINDS)})"
            )
        return v


def _build(sec: FaultBatterySection, ctx: BuildContext) -> FaultBatteryActuator:
    """The actuator of a validated ``[actuator] type = "fault-battery"`` section."""
    n = ctx.count
    if sec.spacecraft > n:
        raise ValueError(
            f"actuator.spacecraft = {sec.spacecraft}: must be in 1..{n} (the plant has {n} "
            "spacecraft)"
        )
    limit = np.inf if sec.saturation is None else sec.saturation
    sat = per_spacecraft(limit, n, "actuator.saturation")
    quantity = getattr(ctx.plant, "quantity", "force")
    return FaultBatteryActuator(
        count=n,
        saturation=as_float(sat),
        fault_kind=as_float(fault_kind_code(sec.kind)),
        **section_floats(sec, "spacecraft", "axis", "onset", "effectiveness", "bias", "period"),
        **section_floats(sec, "duty", "rate", "min_effectiveness"),
        euler_allocation=sec.euler_allocation,
        units="N m" if quantity == "torque" else "N",
    )


register(
    "actuator",
    "fault-battery",
    FaultBatterySection,
    _build,
    "per-axis saturation + one fault (loss of effectiveness, bias, stuck, outage, "
    "intermittent, degrading) on one channel from an onset; kind and numbers are leaves",
)
