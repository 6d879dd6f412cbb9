"""The component catalog: one home module per component type, found from its path.

A scenario names one component type per slot of the closed loop (``[controller] type = "lqr"``). The
type ``name`` of kind ``kind`` lives in one module, its *home*::

    formation_ftc/components/<KIND_PACKAGES[kind]>/<name with '-' as '_'>.py

(``controller`` ``lqr`` -> ``formation_ftc.components.controllers.lqr``). The home holds the type's
equations, its :func:`~formation_ftc.sim.components.component` class, its TOML section (a pydantic
model whose field names are the component's field names, so that the TOML path is the pytree path),
its builder and its registration (:func:`register`). Modules whose name starts with ``_`` hold what
several homes of a kind share and register nothing.

Nothing is listed by hand: :func:`component_type` imports the one home a scenario names, so validating
a scenario imports only the homes of the types it uses (and no JAX: homes import it lazily);
:func:`component_types` (and :func:`type_names`) import every home of a kind (the composed schema,
error messages listing the known types, the conformance tests). A plug-in registers its own types from any module
of its own (its entry point imports it, :func:`formation_ftc.registry.load_plugins`).

A type states what it needs from the other parts of the loop through the
:meth:`~formation_ftc.sim.components.Component.needs` / ``provides`` of the component it builds, which
:meth:`~formation_ftc.sim.loop.ClosedLoop.validate` checks in one place; a builder only turns its
validated section (and the flight knowledge it may read from :class:`BuildContext`) into a component.
"""

from __future__ import annotations

import importlib
import importlib.util
import pkgutil
import re
import sys
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from pydantic import Field, ValidationError, model_validator

from formation_ftc.components._sections import check_rows, per_spacecraft
from formation_ftc.config.base import StrictModel, error_location

__all__ = [
    "SLOTS",
    "KINDS",
    "KIND_PACKAGES",
    "ComponentType",
    "BuildContext",
    "register",
    "component_type",
    "component_types",
    "type_names",
    "home_module",
    "per_spacecraft",
    "builder_input",
    "is_builder_input",
    "validated_section",
    "InitialStateRows",
]

#: slots a composed scenario may fill (plant and controller are required)
SLOTS = (
    "plant",
    "reference",
    "sensors",
    "network",
    "estimator",
    "supervisor",
    "controller",
    "actuator",
)
#: kinds of the catalog: the slots plus ``evaluation`` (a list: ``[[evaluations]]``, truth-side signals
#: for records and metrics only)
KINDS = (*SLOTS, "evaluation")
#: kind -> the subpackage of :mod:`formation_ftc.components` holding its homes (the kind's plural)
KIND_PACKAGES = {kind: kind.removesuffix("s") + "s" for kind in KINDS}
_ROOT = "formation_ftc.components"


@dataclass(frozen=True)
class ComponentType:
    """A registered component type: its section (validates the TOML table without ``type``), its
    builder ``build(section, context) -> component`` and a one-line description."""

    kind: str
    name: str
    section: type[StrictModel]
    build: Callable[[Any, BuildContext], Any]
    description: str
    module: str = ""


_TYPES: dict[tuple[str, str], ComponentType] = {}
#: what a built-in type name looks like (it names a module: nothing else is ever imported)
_TYPE_NAME = re.compile(r"[a-z][a-z0-9]*(-[a-z0-9]+)*")
_LOCK = threading.RLock()


@dataclass(frozen=True)
class BuildContext:
    """What a builder may use besides its own section: the scenario (``section(slot)``: another slot's
    validated section, e.g. the ``[reference]`` orbit a law's on-board model is designed on), the
    spacecraft count, the step [s], the built plant (None while the plant itself is built) and two
    lists a builder may append to: ``evaluations`` (truth-side
    :class:`~formation_ftc.sim.components.Evaluation` components, records and metrics only) and
    ``metrics`` (:class:`~formation_ftc.sim.metrics.Metric` s of a paper's score set, after the
    scenario's own ``[[metrics]]``)."""

    scenario: Any
    count: int  # number of spacecraft (from the plant section)
    dt: float  # step [s]
    plant: Any = None
    evaluations: list = field(default_factory=list)
    metrics: list = field(default_factory=list)

    @property
    def horizon(self) -> float:
        """The scenario's horizon [s]."""
        return float(self.scenario.simulation.horizon)

    def section(self, slot: str) -> Any:
        """The validated section of another slot (None when the slot is empty)."""
        return self.scenario.section(slot)

    def sensed_shapes(self) -> dict[str, tuple[int, ...]] | None:
        """The shapes of what sensors see of the built plant's initial state (its ``sensed_state``), by
        name; None without a plant. A plant that declares them (``sensed_shapes()``: the inertial
        truth, whose initial orbits are JAX computations) is not evaluated: a build that checks a
        composition computes no orbit."""
        plant = self.plant
        if plant is None:
            return None
        declared = getattr(plant, "sensed_shapes", None)
        if declared is not None:
            return dict(declared())
        state = plant.sensed_state(plant.initial_state())
        return {k: np.shape(v) for k, v in state.items()} if isinstance(state, dict) else {}


def home_module(kind: str, name: str) -> str:
    """The module that is the home of ``[kind] type = "name"``.

    Parameters
    ----------
    kind : str
        One of :data:`KINDS`.
    name : str
        The type name.

    Returns
    -------
    str
        The dotted module name.

    Examples
    --------
    >>> home_module("controller", "li2020-adaptive")
    'formation_ftc.components.controllers.li2020_adaptive'
    """
    return f"{_ROOT}.{KIND_PACKAGES[kind]}.{name.replace('-', '_')}"


def _kind_of_home(module: str) -> tuple[str, str] | None:
    """``(kind, module stem)`` when ``module`` is a built-in home (not a shared ``_`` module)."""
    parts = module.split(".")
    if len(parts) != 4 or ".".join(parts[:2]) != _ROOT or parts[3].startswith("_"):
        return None
    kinds = {pkg: kind for kind, pkg in KIND_PACKAGES.items()}
    return (kinds[parts[2]], parts[3]) if parts[2] in kinds else None


def register(
    kind: str,
    name: str,
    section: type[StrictModel],
    build: Callable[[Any, BuildContext], Any],
    description: str,
) -> ComponentType:
    """Make ``[kind] type = "name"`` available in scenarios (called once, by the type's home).

    Parameters
    ----------
    kind : str
        One of :data:`KINDS`.
    name : str
        The type name scenarios use (lower case, words joined by ``-``).
    section : type
        Pydantic model of the TOML table (without its ``type`` key); field names are the component's
        field names, or builder inputs (:func:`builder_input`).
    build : callable
        ``build(section, context) -> component``.
    description : str
        One line for ``formation-ftc schema`` and error messages.

    Returns
    -------
    ComponentType
        The registered entry.

    Raises
    ------
    ValueError
        An unknown kind, or a built-in module registering a type that is not its own (one home per
        type: the module's path must be :func:`home_module` of ``(kind, name)``).

    Examples
    --------
    A plug-in's module registers its types (here a law that commands nothing):

    >>> from formation_ftc.components.controllers.none import ZeroController
    >>> from formation_ftc.config.base import StrictModel
    >>> class Idle(StrictModel):
    ...     pass
    >>> entry = register("controller", "doc-idle", Idle, lambda s, c: ZeroController(count=c.count), "idle")
    >>> component_type("controller", "doc-idle") is entry
    True
    >>> _ = _TYPES.pop(("controller", "doc-idle"))
    """
    if kind not in KINDS:
        raise ValueError(f"unknown kind {kind!r} (kinds: {', '.join(KINDS)})")
    module = sys._getframe(1).f_globals.get("__name__", "")
    home = _kind_of_home(module)
    if home is not None and module != home_module(kind, name):
        raise ValueError(
            f"{module} registers {kind} {name!r}, whose home is {home_module(kind, name)}: one "
            "module per component type, named after it"
        )
    entry = ComponentType(kind, name, section, build, description, module)
    with _LOCK:
        _TYPES[(kind, name)] = entry
    return entry


def _homes(kind: str) -> list[str]:
    """The home modules of ``kind`` in the package (from the file names; nothing imported)."""
    package = importlib.import_module(f"{_ROOT}.{KIND_PACKAGES[kind]}")
    return sorted(
        f"{package.__name__}.{m.name}"
        for m in pkgutil.iter_modules(package.__path__)
        if not m.name.startswith("_") and not m.ispkg
    )


def type_names(kind: str) -> list[str]:
    """Names of the registered types of ``kind`` (every built-in home imported; plug-ins' types
    included), e.g. for an error message listing the known ones.

    Parameters
    ----------
    kind : str
        One of :data:`KINDS`.

    Returns
    -------
    list of str
        The names, sorted.

    Examples
    --------
    >>> "lqr" in type_names("controller")
    True
    """
    return sorted(n for (_, n) in component_types(kind))


def component_type(kind: str, name: str) -> ComponentType | None:
    """The entry of ``[kind] type = "name"`` (None if there is none), importing its home only.

    Parameters
    ----------
    kind : str
        One of :data:`KINDS`.
    name : str
        The type name; only a name of lower-case words joined by ``-`` names a home.

    Returns
    -------
    ComponentType or None
        The registered entry.

    Examples
    --------
    >>> component_type("controller", "lqr").module
    'formation_ftc.components.controllers.lqr'
    >>> component_type("controller", "no-such-law") is None
    True
    """
    if kind not in KINDS:
        return None
    entry = _TYPES.get((kind, name))
    if entry is None and _TYPE_NAME.fullmatch(name):
        module = home_module(kind, name)
        try:
            found = importlib.util.find_spec(module) is not None
        except (ImportError, ValueError):
            found = False
        if found:
            importlib.import_module(module)
            entry = _TYPES.get((kind, name))
    return entry


def component_types(kind: str | None = None) -> dict[tuple[str, str], ComponentType]:
    """Every registered type (of ``kind``), every built-in home imported.

    Parameters
    ----------
    kind : str, optional
        One of :data:`KINDS`; None: every kind.

    Returns
    -------
    dict
        ``(kind, name)`` -> :class:`ComponentType`, sorted.

    Examples
    --------
    >>> ("controller", "lqr") in component_types("controller")
    True
    """
    for k in KINDS if kind is None else (kind,):
        for module in _homes(k):
            importlib.import_module(module)
    return {key: v for key, v in sorted(_TYPES.items()) if kind is None or key[0] == kind}


#: key of a field's JSON-schema extra that marks it as a builder input
_BUILDER_INPUT = "builder_input"


def builder_input(default: Any = ..., **kwargs: Any) -> Any:
    """A section field that is an input of the builder, not a field of the component it builds (a
    design weight the gain is computed from, an orbit radius turned into a mean motion): a campaign
    that samples it builds each run afresh. ``pydantic.Field`` arguments otherwise.

    Parameters
    ----------
    default : Any, optional
        The default (none: the field is required).
    **kwargs
        Further ``pydantic.Field`` arguments (``description``, ``gt``, ...).

    Returns
    -------
    pydantic.fields.FieldInfo
        The field, marked in its JSON-schema extra.

    Examples
    --------
    >>> from formation_ftc.config.base import StrictModel
    >>> class S(StrictModel):
    ...     max_error: float = builder_input(1.0, description="Bryson's largest error [m].")
    >>> is_builder_input(S.model_fields["max_error"])
    True
    """
    extra = dict(kwargs.pop("json_schema_extra", None) or {})
    extra[_BUILDER_INPUT] = True
    return Field(default, json_schema_extra=extra, **kwargs)


def is_builder_input(info: Any) -> bool:
    """Whether a pydantic field (``Model.model_fields[name]``) is a :func:`builder_input`.

    Parameters
    ----------
    info : pydantic.fields.FieldInfo
        The field.

    Returns
    -------
    bool
        True for a builder input.

    Examples
    --------
    >>> from formation_ftc.components.controllers.lqr import LqrSection
    >>> is_builder_input(LqrSection.model_fields["max_acceleration"])
    True
    >>> is_builder_input(LqrSection.model_fields["nominal_mass"])
    False
    """
    extra = getattr(info, "json_schema_extra", None)
    return isinstance(extra, dict) and bool(extra.get(_BUILDER_INPUT))


def validated_section(entry: ComponentType, raw: dict[str, Any], where: str) -> Any:
    """``raw`` (without its ``type`` key) validated by the type's section; one error listing the
    section's validation errors, each named ``where.field[index]: reason``.

    Parameters
    ----------
    entry : ComponentType
        The type.
    raw : dict
        The TOML table (its ``type`` key is ignored).
    where : str
        The table's name in the scenario (``controller``, ``evaluations[1]``), for the error.

    Returns
    -------
    pydantic.BaseModel
        The validated section.

    Raises
    ------
    ValueError
        Every validation error of the table, each named ``where.field``.

    Examples
    --------
    >>> lqr = component_type("controller", "lqr")
    >>> validated_section(lqr, {"type": "lqr", "max_position_error": 1.0,
    ...     "max_velocity_error": 0.01, "max_acceleration": -1.0}, "controller")
    Traceback (most recent call last):
    ...
    ValueError: controller.max_acceleration: every value must be finite and > 0 (got -1.0)
    """
    try:
        return entry.section.model_validate({k: v for k, v in raw.items() if k != "type"})
    except ValidationError as exc:
        lines = []
        for err in exc.errors():
            loc, msg = error_location(err), err["msg"].removeprefix("Value error, ")
            lines.append(f"{where}.{loc}: {msg}" if loc else f"{where}: {msg}")
        raise ValueError("; ".join(lines)) from None


class InitialStateRows(StrictModel):
    """A plant section of N spacecraft given by their initial states, one row each (N is the number of
    ``initial_position`` rows; ``initial_velocity``, when given, has as many). Subclasses restate the
    two fields with their frame in the description."""

    initial_position: list[tuple[float, float, float]] = Field(
        description="Initial position per spacecraft [m]."
    )
    initial_velocity: list[tuple[float, float, float]] | None = Field(
        None, description="Initial velocity per spacecraft [m/s] (default 0)."
    )

    @model_validator(mode="after")
    def _rows(self):
        n = len(self.initial_position)
        if n < 1:
            raise ValueError("initial_position: at least one spacecraft")
        check_rows(self, ["initial_velocity"], n)
        return self

    @property
    def count(self) -> int:
        """Number of spacecraft [-]."""
        return len(self.initial_position)
