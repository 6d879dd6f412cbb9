"""A law wrapped by another component of its slot (:class:`WrappedLaw`: everything passes through to it),
and the first such wrapper: an acceleration law flying a force-driven plant, the command scaled by each
spacecraft's nominal mass."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from formation_ftc.components._pass_through import PassThrough
from formation_ftc.components._sections import check_nominal_masses
from formation_ftc.sim.components import (
    CompositionError,
    Controller,
    FlightInputs,
    Signal,
    component,
)
from formation_ftc.sim.contract import VEC

__all__ = [
    "WrappedLaw",
    "AccelerationToForce",
    "TrackingAccelerationToForce",
    "force_from_acceleration",
    "wrapper_for",
    "ACCELERATION_COMMAND_SIGNAL",
]

#: the wrapped law's own command, recorded next to the loop's ``command`` (the force)
ACCELERATION_COMMAND_SIGNAL = "acceleration_command"


@component
class WrappedLaw(PassThrough, Controller):  # type: ignore[override]  # a property holds_exogenous
    """A controller that wraps the law ``law``: its structure (sampling, states, messages, time signals,
    recorded signals, coordinates, conditions, what it needs and provides) is the law's; a wrapper
    that changes the command states :meth:`command` and ``recorded_command``, the signal (name, units,
    long name) under which the law's own command is recorded next to the loop's."""

    law: Controller
    recorded_command: ClassVar[tuple[str, str, str] | None] = None
    wrapped_field = "law"

    def command(self, u, inputs: FlightInputs):
        """The wrapper's command from the law's command ``u`` (unchanged here)."""
        return u

    @property
    def sampled(self) -> bool:
        return self.law.sampled

    @property
    def count(self) -> int:
        return int(self.law.count)  # type: ignore[attr-defined]  # every translational law has a count

    @property
    def uses_messages(self) -> bool:
        return bool(getattr(self.law, "uses_messages", False))

    def needs(self) -> dict[str, str]:
        return self.law.needs()

    def provides(self) -> frozenset[str]:
        return self.law.provides()

    def initial_state(self):
        return self.law.initial_state()

    def message(self, t, inputs: FlightInputs):
        return self.law.message(t, inputs)

    def output(self, t, state, inputs: FlightInputs):
        u, nxt, out = self.law.output(t, state, inputs)
        if self.recorded_command is None:
            return u, nxt, out
        return self.command(u, inputs), nxt, {**out, self.recorded_command[0]: u}

    def signals(self):
        own = self.recorded_command
        extra = () if own is None else (Signal(own[0], VEC, *own[1:]),)
        return tuple(self.law.signals()) + extra


@component
class AccelerationToForce(WrappedLaw):
    """A law that commands accelerations u_i [m/s^2] (``quantity = "acceleration"``, e.g. a
    deep-space double-integrator law) turned into the force command a force-driven plant needs::

        f_i = m_i^nom u_i                                                              [N]

    ``nominal_mass`` (N,) [kg] is what the flight side knows about the spacecraft masses (a design
    number on board, not the plant's true mass): with a true mass m_i the plant receives the
    acceleration (m_i^nom / m_i) u_i, i.e. a mass error acts like an actuator-gain error the law does
    not know. Everything else (sampling, states, messages, time signals, recorded signals, conditions,
    what it needs and provides) is the wrapped law's; the law's own command is recorded as
    ``acceleration_command``. Use :func:`force_from_acceleration` to build one (it keeps the law's
    position objective, if any).
    """

    nominal_mass: Any  # (N,) [kg]

    quantity = "force"
    recorded_command = (
        ACCELERATION_COMMAND_SIGNAL,
        "m s-2",
        "acceleration commanded by the law (before the nominal-mass scaling)",
    )

    def __post_init__(self) -> None:
        law = self.law
        if not isinstance(law, Controller):
            return  # pytree reconstruction with placeholders
        if law.quantity != "acceleration":
            raise CompositionError(
                f"AccelerationToForce scales an acceleration command by the nominal mass, but "
                f"controller {type(law).__name__} commands a {law.quantity}"
            )

    def command(self, u, inputs: FlightInputs):
        return self.nominal_mass[:, None] * u  # f_i = m_i^nom u_i


@component
class TrackingAccelerationToForce(AccelerationToForce):
    """:class:`AccelerationToForce` for a law with a position objective: the loop records
    ``position_error`` against the law's desired position."""

    def desired_position_at(self, exogenous):
        return self.law.desired_position_at(exogenous)


def force_from_acceleration(law: Controller, nominal_mass: Any) -> AccelerationToForce:
    """``law`` (acceleration command) driving a force plant with the flight side's ``nominal_mass``
    (N,) [kg], checked here (one finite mass > 0 per spacecraft of the law; not on pytree
    reconstruction, where a batch stacks the leaves); the law's position objective, if it declares
    one, is kept.

    Parameters
    ----------
    law : Controller
        A law with ``quantity = "acceleration"`` and a ``count`` of N spacecraft.
    nominal_mass : array_like, shape (N,)
        Nominal masses known on board (finite, > 0) [kg].

    Returns
    -------
    AccelerationToForce
        A :class:`TrackingAccelerationToForce` when ``law`` declares a desired position.

    Raises
    ------
    CompositionError
        Not one finite mass > 0 per spacecraft, or a law that does not command accelerations.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.controllers._acceleration_to_force import force_from_acceleration
    >>> from formation_ftc.components.controllers.none import FreeDrift
    >>> ctrl = force_from_acceleration(FreeDrift(count=2), np.array([100.0, 120.0]))
    >>> type(ctrl).__name__, ctrl.quantity, ctrl.count
    ('AccelerationToForce', 'force', 2)
    >>> force_from_acceleration(FreeDrift(count=2), np.array([100.0]))
    Traceback (most recent call last):
    ...
    formation_ftc.sim.components.CompositionError: AccelerationToForce: nominal masses [100.0] kg for controller FreeDrift of 2 spacecraft (need 2, each > 0)
    """
    m = np.asarray(nominal_mass, dtype=float)
    n = int(law.count)  # type: ignore[attr-defined]  # every translational law has a count
    check_nominal_masses(
        m, n, "AccelerationToForce", f"controller {type(law).__name__}", f"need {n}, each > 0"
    )
    cls = wrapper_for(law, AccelerationToForce, TrackingAccelerationToForce)
    return cls(law=law, nominal_mass=nominal_mass)


def wrapper_for(law: Controller, plain: type, tracking: type) -> type:
    """``tracking`` (a wrapper that passes the law's position objective on) when ``law`` declares a
    desired position, else ``plain``.

    Parameters
    ----------
    law : Controller
        The law to wrap.
    plain, tracking : type
        The wrapper classes without and with ``desired_position_at``.

    Returns
    -------
    type
        The wrapper class for ``law``.

    Examples
    --------
    >>> from formation_ftc.components.controllers.none import FreeDrift
    >>> wrapper_for(FreeDrift(count=1), AccelerationToForce, TrackingAccelerationToForce).__name__
    'AccelerationToForce'
    """
    tracks = type(law).desired_position_at is not Controller.desired_position_at
    return tracking if tracks else plain
