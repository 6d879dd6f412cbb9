"""What a component built around another one of its slot passes through unchanged (the wrapped one is
its field named by ``wrapped_field``): an actuator acting through an inner chain, a law wrapped by a
command conversion, an estimator driven by another model or filter."""

from __future__ import annotations

from typing import Any, ClassVar

__all__ = ["PassThrough"]


class PassThrough:
    """Mixin (listed before the slot's base class): the spacecraft count, the time signals, the
    coordinates and the conditions are those of the wrapped component (the field ``wrapped_field``)."""

    wrapped_field: ClassVar[str] = "inner"

    @property
    def wrapped(self) -> Any:
        """The wrapped component."""
        return getattr(self, self.wrapped_field)

    @property
    def count(self) -> int | None:
        return getattr(self.wrapped, "count", None)

    @property
    def holds_exogenous(self) -> bool:
        return bool(self.wrapped.holds_exogenous)

    def exogenous(self, t):
        return self.wrapped.exogenous(t)

    def held_exogenous(self, step):
        return self.wrapped.held_exogenous(step)

    def coords(self):
        return self.wrapped.coords()

    def conditions(self, loop) -> list:
        conds = getattr(self.wrapped, "conditions", None)
        return list(conds(loop)) if callable(conds) else []
