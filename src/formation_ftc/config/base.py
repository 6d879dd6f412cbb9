"""Typed scenario configuration (pydantic v2): the sections every scenario has.

A scenario file is TOML. Its ``[scenario]`` table may name the ``method`` (default ``"composed"``, the
components of the file's slot tables); that method's schema (a subclass of :class:`ScenarioBase`)
validates the whole file.
Unknown fields are rejected (``extra="forbid"``), every numeric field carries its unit in its
description, and cross-field rules (the step divides the horizon, matrix sizes match the number of
spacecraft) are model validators whose messages name the field.

Values are strict: a boolean is never accepted as a number (``horizon = true`` is an error, not 1.0),
floats must be finite (``inf``/``nan`` are refused for every physical quantity) and the run seed is
bounded to the 32-bit seeds the random generators take.
"""

from __future__ import annotations

import math
import operator
import typing
from collections.abc import Callable
from typing import Annotated, Any

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    ValidationError,
    ValidationInfo,
    field_validator,
    model_validator,
)
from pydantic.fields import FieldInfo
from pydantic_core import ErrorDetails, PydanticCustomError

from formation_ftc.core.expressions import ExpressionError, compile_expression

__all__ = [
    "StrictModel",
    "ScenarioMeta",
    "SimulationSection",
    "ScenarioBase",
    "ExprText",
    "expression_validator",
    "MAX_SEED",
    "error_location",
    "validation_message",
    "field_info",
    "field_bounds",
]

#: largest run seed [-]: seeds are stored as unsigned 32-bit integers for the random generators
MAX_SEED = 2**32 - 1


def _allows_bool(annotation: Any) -> bool:
    """Whether a field annotation admits a boolean anywhere (bool, Any, unions and containers of them)."""
    if annotation is bool or annotation is Any or annotation is object:
        return True
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return True  # a nested model checks its own fields
    origin = typing.get_origin(annotation)
    if origin is Annotated:
        return _allows_bool(typing.get_args(annotation)[0])
    # unions and containers (every generic alias has an origin)
    args = typing.get_args(annotation)
    return origin is not None and any(_allows_bool(a) for a in args if a is not Ellipsis)


def _mentions_float(annotation: Any) -> bool:
    """Whether a field annotation admits a float anywhere (float, unions and containers of it)."""
    if annotation is float:
        return True
    return any(_mentions_float(a) for a in typing.get_args(annotation) if a is not Ellipsis)


def _find_bad_number(value: Any, *, booleans: bool, non_finite: bool) -> tuple[str, Any] | None:
    """``(index path, item)`` of the first boolean (with ``booleans``) or nan/inf (with ``non_finite``)
    inside the lists/tuples of ``value``, e.g. ``("[1][2]", nan)``; None when there is none."""
    stack: list[tuple[Any, str]] = [(value, "")]
    while stack:
        v, p = stack.pop()
        if isinstance(v, bool):
            if booleans:
                return p, v
        elif isinstance(v, float):
            if non_finite and not math.isfinite(v):
                return p, v
        elif isinstance(v, list | tuple):
            stack.extend((x, f"{p}[{k}]") for k, x in reversed(list(enumerate(v))))
    return None


#: pydantic's numeric bounds: (constraint attribute, relation as printed, the relation's test)
_BOUNDS = (
    ("gt", ">", operator.gt),
    ("ge", ">=", operator.ge),
    ("lt", "<", operator.lt),
    ("le", "<=", operator.le),
)


def field_bounds(field: FieldInfo) -> list[tuple[Any, str, Callable[[Any, Any], Any]]]:
    """``(bound, relation, test)`` of every numeric bound ``field`` declares (``Field(gt=0)`` ->
    ``(0, ">", operator.gt)``; ``test(value, bound)`` is whether a value respects it)."""
    return [
        (getattr(c, name), op, test)
        for c in field.metadata
        for name, op, test in _BOUNDS
        if getattr(c, name, None) is not None
    ]


def _allowed_range(field: FieldInfo) -> str:
    """The range a field's numbers must lie in, for messages: ``a finite number > 0``."""
    return ", ".join(["a finite number", *(f"{op} {b}" for b, op, _ in field_bounds(field))])


def error_location(err: ErrorDetails) -> str:
    """Location of a pydantic error, list indices in brackets, down to the refused list item when the
    error names one: ``faults[0].bias``, ``magnitude[1][2]``."""
    loc = "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in err["loc"]).lstrip(".")
    return loc + str(err.get("ctx", {}).get("index", ""))


def validation_message(exc: ValidationError, head: str, unknown: str, root: str = "<root>") -> str:
    """A pydantic error as lines for the user: ``head (N error(s))``, then ``  field LOC: message``
    per error (``unknown`` for an unknown field; an error without location is at ``root``, or has no
    ``field`` part when ``root`` is "")."""
    lines = [f"{head} ({exc.error_count()} error(s))"]
    for err in exc.errors():
        loc = error_location(err) or root
        msg = (
            unknown
            if err["type"] == "extra_forbidden"
            else err["msg"].removeprefix("Value error, ")
        )
        lines.append(f"  field {loc}: {msg}" if loc else f"  {msg}")
    return "\n".join(lines)


def field_info(model: Any, path: str) -> FieldInfo | None:
    """The field of the pydantic ``model`` that the dotted ``path`` names (list indices skipped; a
    field whose type is, or is a union with, a model is entered), or None when it names none."""
    info = None
    for part in path.split("."):
        if part.isdigit():
            continue
        fields = getattr(model, "model_fields", None)
        if not fields or part not in fields:
            return None
        info, ann = fields[part], fields[part].annotation
        model = next((a for a in getattr(ann, "__args__", ()) if hasattr(a, "model_fields")), ann)
    return info


class StrictModel(BaseModel):
    """Base for every configuration model: unknown fields are errors, assignments are validated."""

    model_config = ConfigDict(
        extra="forbid", validate_assignment=True, frozen=False, allow_inf_nan=False
    )

    @field_validator("*", mode="before")
    @classmethod
    def _numbers_in_lists(cls, v: Any, info: ValidationInfo) -> Any:
        """Booleans are not numbers: refuse ``true``/``false`` where the field takes no boolean. Every
        list item obeys the scalar rule: a field that takes a float refuses nan/inf in its lists too,
        whatever the lists' declared item type (``magnitude = [0.0, nan]`` like ``magnitude = nan``)."""
        if not isinstance(v, bool | list | tuple) or info.field_name is None:
            return v
        field = cls.model_fields.get(info.field_name)
        if field is None:
            return v
        bad = _find_bad_number(
            v,
            booleans=not _allows_bool(field.annotation),
            non_finite=_mentions_float(field.annotation),
        )
        if bad is None:
            return v
        index, item = bad
        if isinstance(item, bool):
            raise ValueError(
                f"expected a number{' at ' + index if index else ''}, got a boolean "
                f"(booleans are not numbers)"
            )
        raise PydanticCustomError(
            "finite_number",
            "{value} is refused: must be {allowed} (never nan or inf)",
            {"index": index, "value": repr(item), "allowed": _allowed_range(field)},
        )


def expression_validator(variables: tuple[str, ...] = ("t", "i")):
    """A ``BeforeValidator`` that parses an expression string (or number) and keeps its text."""

    def _check(v: Any) -> str:
        if isinstance(v, bool):
            raise ValueError("expected an expression string or a number, got a boolean")
        if isinstance(v, int | float):
            try:
                x = float(v)
            except OverflowError:
                x = math.inf
            if not math.isfinite(x):
                raise ValueError(f"expected a finite number, got {v!r}")
            return repr(x)
        if not isinstance(v, str):
            raise ValueError(f"expected an expression string or a number, got {type(v).__name__}")
        try:
            compile_expression(v, variables)
        except ExpressionError as exc:
            raise ValueError(str(exc)) from None
        return v

    return BeforeValidator(_check)


#: A math expression in ``t`` [s] and ``i`` (1-based spacecraft number); see core.expressions.
ExprText = Annotated[str, expression_validator(("t", "i"))]


class ScenarioMeta(StrictModel):
    name: str = Field(description="Scenario name (built-in scenarios use paper-prefixed names).")
    method: str = Field(
        "composed",
        description="Method that simulates this scenario: 'composed' (the default, so the line may be "
        "left out) or one a plug-in registers.",
    )
    description: str = Field("", description="One-line description shown by `formation-ftc list`.")
    paper: str | None = Field(
        None, description="Paper short name this scenario reproduces, if any."
    )


class SimulationSection(StrictModel):
    horizon: float = Field(gt=0, description="Simulated time span [s].")
    dt: float = Field(gt=0, description="Fixed integration step [s]; must divide the horizon.")
    record_every: int = Field(
        1, ge=1, description="Record every k-th step (output decimation) [-]."
    )
    seed: int = Field(
        0, ge=0, le=MAX_SEED, description="Root random seed of the run, 0 <= seed < 2**32 [-]."
    )
    unroll: int = Field(
        1, ge=1, le=64, description="lax.scan unroll factor (performance only) [-]."
    )
    max_position: float = Field(
        1.0e6,
        gt=0,
        description=(
            "Admissible set: a run whose spacecraft position (relative to the formation frame's origin) exceeds "
            "this magnitude has diverged and stops with a diagnostic [m]."
        ),
    )
    max_velocity: float = Field(
        1.0e4,
        gt=0,
        description="Admissible set: a run whose spacecraft velocity exceeds this magnitude has diverged [m/s].",
    )
    max_rate: float = Field(
        100.0,
        gt=0,
        description="Admissible set: a run whose spacecraft body rate exceeds this magnitude has diverged [rad/s].",
    )
    max_pitch: float = Field(
        1.5607963267948966,
        gt=0,
        lt=1.5707963267948966,
        description=(
            "Admissible set: a run whose 3-2-1 Euler pitch exceeds this magnitude has diverged (the Euler-angle "
            "kinematics are singular at pi/2; default pi/2 - 0.01) [rad]."
        ),
    )

    @model_validator(mode="after")
    def _step_divides_horizon(self) -> SimulationSection:
        ratio = self.horizon / self.dt
        if not math.isfinite(ratio) or ratio > 2**53:
            raise ValueError(
                f"simulation.horizon / simulation.dt = {self.horizon:g} / {self.dt:g} s is not a "
                f"countable number of steps (at most 2**53); shorten the horizon or enlarge the step"
            )
        n = round(ratio)
        if n < 1 or abs(n * self.dt - self.horizon) > 1e-9 * max(self.horizon, 1.0):
            raise ValueError(
                f"simulation.dt = {self.dt} s must divide simulation.horizon = {self.horizon} s "
                f"(horizon/dt = {self.horizon / self.dt:.6g} is not an integer)"
            )
        if n % self.record_every:
            raise ValueError(
                f"simulation.record_every = {self.record_every} must divide the number of steps "
                f"horizon/dt = {n}"
            )
        return self

    @property
    def n_steps(self) -> int:
        """horizon / dt [-]."""
        return round(self.horizon / self.dt)


class ScenarioBase(StrictModel):
    """Sections common to every scenario; methods subclass this with their own sections."""

    scenario: ScenarioMeta
    simulation: SimulationSection

    def __repr__(self) -> str:
        sim = self.simulation
        return (
            f"<{type(self).__name__} {self.scenario.name!r}: method {self.scenario.method}, horizon "
            f"{sim.horizon:g} s, dt {sim.dt:g} s ({sim.n_steps:,} steps), seed {sim.seed}>"
        )

    def _repr_html_(self) -> str:
        """Jupyter: name, method, horizon and step, seed, and each section's type (formation_ftc.display)."""
        from formation_ftc.display import card_html

        meta, sim = self.scenario, self.simulation
        fields = [("method", meta.method)] + ([("paper", meta.paper)] if meta.paper else [])
        fields += [
            ("horizon", f"{sim.horizon:g} s"),
            ("step", f"{sim.dt:g} s ({sim.n_steps:,} steps, recorded every {sim.record_every})"),
            ("seed", str(sim.seed)),
        ]

        def label(v: Any) -> str:  # a section's or list item's component type (or name)
            d = v if isinstance(v, dict) else v.__dict__ if isinstance(v, BaseModel) else {}
            return str(d.get("type") or d.get("name") or type(v).__name__)

        rows = []
        for name in type(self).model_fields:
            value = getattr(self, name)
            if name not in ("scenario", "simulation") and value:
                items = value if isinstance(value, list) else [value]  # metrics, evaluations
                rows.append([name, ", ".join(label(v) for v in items)])
        return card_html(
            f"scenario {meta.name}", meta.description, fields, ["section", "type or names"], rows
        )
