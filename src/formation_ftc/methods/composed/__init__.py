"""Method ``composed``: any law on any compatible plant with any fault, from a scenario file.

A composed scenario names one component type per slot of the closed loop and gives its parameters::

    [scenario]
    method = "composed"
    [plant]            type = "clohessy-wiltshire"   ...its fields
    [reference]        type = "circular"             (optional)
    [sensors]          type = "relative-state"       (optional, default: exact state)
    [network]          type = "graph"                (optional)
    [estimator]        type = ...                    (optional)
    [supervisor]       type = ...                    (optional)
    [controller]       type = "li2020-adaptive"      ...its fields
    [actuator]         type = "thruster-bias"        (optional, default: ideal)
    [[evaluations]]    type = "formation-scores"     (optional: truth-side score signals)
    [[metrics]]        name, signal, reduce, ...     (optional, computed at every step)

Every component type is registered in a catalog (:func:`register_component_type`) with a pydantic
section (validated like every scenario section: unknown fields, wrong types and out-of-range values are
errors naming ``slot.field``) and a builder. After the sections, the loop itself is assembled and
checked (:meth:`~formation_ftc.sim.loop.ClosedLoop.validate`): a composition that cannot work -- an
attitude law on a translational plant, a delayed network with a law that exchanges no messages,
mismatched spacecraft counts, a plant that needs a reference orbit without one -- is rejected at
validation, before any computation, with a message naming both parts and why (exit code 2).

Catalog modules (``catalog_*.py``) register the built-in types; a plug-in may register more.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Literal, cast

import numpy as np
from pydantic import Field, PrivateAttr, ValidationInfo, model_validator

from formation_ftc.components import _registry
from formation_ftc.components._registry import (
    KINDS,
    SLOTS,
    BuildContext,
    ComponentType,
    InitialStateRows,
    per_spacecraft,
    register,
)
from formation_ftc.components._registry import validated_section as _validated_section
from formation_ftc.config.base import ScenarioBase, StrictModel
from formation_ftc.registry import Condition, Method, register_method, resolve_reference
from formation_ftc.sim.contract import (
    BLOCK_REDUCTIONS,
    REDUCTIONS,
    SPACECRAFT_REDUCTIONS,
    CompositionError,
    as_float,
)

# the loop and its components import JAX: only make_loop, build and check import them
if TYPE_CHECKING:
    from formation_ftc.sim.loop import ClosedLoop

__all__ = [
    "ComposedScenario",
    "ComponentType",
    "BuildContext",
    "register_component_type",
    "component_types",
    "component_type",
    "make_loop",
    "build",
    "SLOTS",
    "KINDS",
    "per_spacecraft",
    "register_paper_figures",
    "register_conditions",
    "composed_json_schema",
    "InitialStateRows",
]


register_component_type = register
component_types = _registry.component_types
component_type = _registry.component_type


def _known(kind: str) -> str:
    """The type names of ``kind`` for an error message (imports every home of the kind's types)."""
    return ", ".join(_registry.type_names(kind)) or "none registered"


def _section(kind: str, raw: dict[str, Any], where: str) -> Any:
    """``raw`` validated as the section of its ``type`` of component ``kind`` (messages name ``where``:
    the slot, or ``evaluations[j]``)."""
    name = raw.get("type")
    if name is None and kind in SLOTS:
        raise ValueError(f"{where}.type is required (one of: {_known(kind)})")
    entry = component_type(kind, str(name))
    if entry is None:
        article = "an" if kind == "evaluation" else "a"
        raise ValueError(
            f"{where}.type = {name!r} is not {article} {kind} type (known: {_known(kind)})"
        )
    return _validated_section(entry, raw, where)


class MetricSection(StrictModel):
    """One metric computed at every step inside the run (see ``formation_ftc.sim.metrics``)."""

    name: str = Field(
        description="Metric name (per-spacecraft metrics get _sc1, _sc2, ... appended)."
    )
    signal: str = Field(
        "", description="Name of a recorded signal of the composed loop (not with reduce = 'stl')."
    )
    reduce: str = Field("max", description=f"Time reduction: one of {', '.join(REDUCTIONS)}.")
    norm: bool = Field(False, description="Euclidean norm over the signal's last axis first.")
    spacecraft: str = Field(
        "none", description=f"Spacecraft reduction: one of {', '.join(SPACECRAFT_REDUCTIONS)}."
    )
    units: str = Field("1", description="Units of the metric (UDUNITS).")
    start: float = Field(0.0, description="Window start [s].")
    end: float | None = Field(None, description="Window end [s] (omit: until the horizon).")
    threshold: float = Field(0.0, description="Threshold of the 'settle' reduction [signal units].")
    norm_ord: Literal["2", "inf"] = Field(
        "2", description="Norm of `norm`: '2' Euclidean, 'inf' largest |component|."
    )
    gate: str | None = Field(
        None, description="Name of a recorded signal: only samples where it is true count."
    )
    block: int = Field(
        0,
        ge=0,
        le=10_000_000,
        description=(
            "Block length of the 'block_rms' / 'block_dev_rms' reductions [steps] (>= 1 for those; 0 otherwise)."
        ),
    )
    formula: str | None = Field(
        None,
        description="Signal temporal logic formula of reduce = 'stl', e.g. "
        "'F[0,300](G(shape_error <= 1))' (docs/requirements.md); the metric is its robustness.",
    )

    @model_validator(mode="after")
    def _known(self):
        if self.reduce not in REDUCTIONS:
            raise ValueError(f"reduce = {self.reduce!r}: must be one of {', '.join(REDUCTIONS)}")
        if self.reduce == "stl":
            if self.formula is None:
                raise ValueError("formula: reduce = 'stl' needs an STL formula")
            from formation_ftc.sim.stl import parse

            parse(self.formula)  # StlError (a ValueError) names the position
        elif self.formula is not None:
            raise ValueError(f"formula: only with reduce = 'stl' (reduce is {self.reduce!r})")
        elif not self.signal:
            raise ValueError("signal: required (the recorded signal the metric reduces)")
        if self.reduce in BLOCK_REDUCTIONS and self.block < 1:
            raise ValueError(
                f"block = {self.block}: reduce = {self.reduce!r} needs a block of >= 1 steps "
                "(e.g. block = 100)"
            )
        if self.spacecraft not in SPACECRAFT_REDUCTIONS:
            raise ValueError(
                f"spacecraft = {self.spacecraft!r}: must be one of {', '.join(SPACECRAFT_REDUCTIONS)}"
            )
        return self


class ComposedScenario(ScenarioBase):
    """A closed loop assembled from catalog components, one table per slot."""

    plant: dict[str, Any] = Field(description="Truth plant: `type` and that type's fields.")
    controller: dict[str, Any] = Field(description="Control law: `type` and that type's fields.")
    reference: dict[str, Any] | None = Field(None, description="Reference orbit (optional).")
    sensors: dict[str, Any] | None = Field(
        None, description="Sensors (optional; default: exact state)."
    )
    network: dict[str, Any] | None = Field(None, description="Communication network (optional).")
    estimator: dict[str, Any] | None = Field(None, description="Observer / FDI (optional).")
    supervisor: dict[str, Any] | None = Field(None, description="Supervisor (optional).")
    actuator: dict[str, Any] | None = Field(
        None, description="Actuator chain with faults (optional)."
    )
    evaluations: list[dict[str, Any]] = Field(
        default_factory=list,
        description=(
            "Truth-side evaluation signals (records and metrics only): `type` and that type's fields."
        ),
    )
    metrics: list[MetricSection] = Field(
        default_factory=list, description="Metrics computed at every step."
    )
    _sections: dict[str, Any] = PrivateAttr(default_factory=dict)
    _evaluation_sections: list[tuple[str, Any]] = PrivateAttr(default_factory=list)
    _evaluation_labels: list[str] = PrivateAttr(default_factory=list)

    @model_validator(mode="after")
    def _compose(self, info: ValidationInfo) -> ComposedScenario:
        # only the homes of the named types are imported (every home of a slot for a message)
        self._sections = {
            slot: _section(slot, getattr(self, slot), slot)
            for slot in SLOTS
            if getattr(self, slot) is not None
        }
        self._evaluation_sections = [
            (str(raw.get("type")), _section("evaluation", raw, f"evaluations[{j}]"))
            for j, raw in enumerate(self.evaluations)
        ]
        if isinstance(info.context, dict) and info.context.get("build") is False:
            return self  # fields only (`show`): check, run and campaigns build the loop
        try:
            make_loop(self).validate(self.labels())
        except CompositionError as exc:
            raise ValueError(f"components do not fit together: {exc}") from None
        return self

    def section(self, slot: str) -> Any:
        return self._sections.get(slot)

    def labels(self) -> dict[str, str]:
        """Slot -> the type name this scenario gives it, and ``evaluations[k]`` (the loop's k-th
        evaluation) -> which type added it, once the loop is built (for messages)."""
        out = {slot: str(getattr(self, slot)["type"]) for slot in SLOTS if getattr(self, slot)}
        out |= {f"evaluations[{k}]": label for k, label in enumerate(self._evaluation_labels)}
        return out

    def type_of(self, slot: str) -> str | None:
        raw = getattr(self, slot)
        return None if raw is None else str(raw.get("type"))


def composed_json_schema() -> dict[str, Any]:
    """JSON Schema of a composed scenario file in which every slot table (and every
    ``[[evaluations]]`` item) is one of the catalog's component types: a ``oneOf`` over the types of
    that slot, each the type's section with ``type`` fixed to its name (for editor completion and
    validation; ``formation-ftc schema composed``).

    Returns
    -------
    dict
        The schema (draft 2020-12 keywords, ``$defs`` merged).

    Examples
    --------
    >>> schema = composed_json_schema()
    >>> any(o["properties"]["type"]["const"] == "pd" for o in schema["properties"]["controller"]["oneOf"])
    True
    """
    schema = ComposedScenario.model_json_schema()
    defs = schema.setdefault("$defs", {})

    def one_of(kind: str) -> dict[str, Any]:
        options = []
        for (_, name), entry in sorted(component_types(kind).items()):
            sub = entry.section.model_json_schema(ref_template="#/$defs/{model}")
            defs.update(sub.pop("$defs", {}))
            sub["properties"] = {
                "type": {"const": name, "description": entry.description},
                **sub.get("properties", {}),
            }
            sub["required"] = ["type", *sub.get("required", [])]
            sub["title"] = f"{kind} {name}"
            options.append(sub)
        return {"oneOf": options}

    for slot in SLOTS:
        description = schema["properties"][slot].get("description", "")
        schema["properties"][slot] = {"description": description, **one_of(slot)}
    ev = schema["properties"]["evaluations"]
    schema["properties"]["evaluations"] = {
        "description": ev.get("description", ""),
        "type": "array",
        "items": one_of("evaluation"),
    }
    return schema


def make_loop(s: ComposedScenario) -> ClosedLoop:
    """The composed scenario's closed loop (components built from their sections)."""
    from formation_ftc.components.sensors.relative_state import ExactRelativeStateSensors
    from formation_ftc.sim.components import Plant
    from formation_ftc.sim.loop import ClosedLoop
    from formation_ftc.sim.metrics import Metric

    plant_entry = cast(ComponentType, component_type("plant", cast(str, s.type_of("plant"))))
    plant_section = s.section("plant")
    count = getattr(plant_section, "count", None)  # else one mass per spacecraft
    count = int(len(getattr(plant_section, "mass", []) or []) if count is None else count)
    ctx = BuildContext(scenario=s, count=count, dt=float(s.simulation.dt))
    parts: dict[str, Any] = {"plant": plant_entry.build(plant_section, ctx)}
    ctx = BuildContext(
        scenario=s, count=parts["plant"].count, dt=float(s.simulation.dt), plant=parts["plant"]
    )
    # what each evaluation of the loop is called in messages: the type that added it
    added_by: list[str] = []
    for slot in SLOTS[1:]:
        name = s.type_of(slot)
        if name is None:
            continue
        parts[slot] = cast(ComponentType, component_type(slot, name)).build(s.section(slot), ctx)
        added_by += [f"{slot} {name}'s evaluation"] * (len(ctx.evaluations) - len(added_by))
    # evaluations after every slot: they read its signals
    for j, (name, section) in enumerate(s._evaluation_sections):
        ev = cast(ComponentType, component_type("evaluation", name)).build(section, ctx)
        if ev is not None:  # None: the type only declares metrics (ctx.metrics)
            ctx.evaluations.append(ev)
        added_by += [f"evaluations[{j}] {name}"] * (len(ctx.evaluations) - len(added_by))
    s._evaluation_labels = added_by
    if "sensors" not in parts and type(parts["plant"]).position is not Plant.position:
        # translational plants: the flight side measures the exact (N, 6) relative state by default
        parts["sensors"] = ExactRelativeStateSensors(count=ctx.count)
    # a metric section's fields are the Metric's, its window and threshold as traced floats
    metrics = (
        *(
            Metric(
                **{
                    **dict(m),
                    "start": as_float(m.start),
                    "end": as_float(math.inf if m.end is None else m.end),
                    "threshold": as_float(m.threshold),
                }
            )
            for m in s.metrics
        ),
        *ctx.metrics,
    )
    return ClosedLoop.from_simulation(
        s.simulation, **parts, metrics=metrics, evaluations=tuple(ctx.evaluations)
    )


def build(s: ComposedScenario) -> ClosedLoop:
    """The composed scenario's loop, its components checked against each other."""
    return make_loop(s).validate(s.labels())


#: conditions of component types: (kind, name) -> [fn(scenario, loop) -> [Condition]]
_CONDITIONS: dict[tuple[str, str], list[Callable[[ComposedScenario, ClosedLoop], list] | str]] = {}


def register_conditions(
    kind: str, name: str, conditions: Callable[[ComposedScenario, ClosedLoop], list] | str
) -> None:
    """``formation-ftc check`` of every composed scenario whose ``[kind]`` is of type ``name`` also
    states ``conditions(scenario, loop)`` (e.g. a paper's theorem conditions for its law, registered by
    the paper's package, which may return ``[]`` where the composition is outside the theorem).
    ``conditions`` may be a ``"module:attribute"`` reference, imported by the first check that needs it
    (:func:`formation_ftc.registry.resolve_reference`)."""
    _CONDITIONS.setdefault((kind, name), []).append(conditions)


def check(s: ComposedScenario) -> list[Condition]:
    """Conditions every composed loop can state: the composition fits, and the RK4 step against the
    fastest linearised closed-loop mode where the components expose one."""
    loop = make_loop(s)
    parts = ", ".join(f"{slot} {s.type_of(slot)}" for slot in SLOTS if s.type_of(slot))
    out = [
        Condition(
            name="components fit together",
            reference="component contract",
            value=parts,
            requirement="compatible quantities, counts, messages, reference",
            holds=True,
            required=True,
            basis="exact",
            detail="exact: structural check of the composition (done when the loop is built)",
        )
    ]
    for slot in SLOTS:
        comp = getattr(loop, slot)
        conds = getattr(comp, "conditions", None)
        if callable(conds):
            out += list(conds(loop))
    for slot in KINDS:
        names = [s.type_of(slot)] if slot in SLOTS else [n for n, _ in s._evaluation_sections]
        for name in names:
            for fn in _CONDITIONS.get((slot, str(name)), []):
                out += list(resolve_reference(fn)(s, loop))
    return out


#: figure makers of papers (``[scenario] paper = "<name>"``): ``fn(ds, scenario, out_dir) -> paths``
_PAPER_FIGURES: dict[str, Callable[[Any, ComposedScenario, Any], list] | str] = {}


def register_paper_figures(
    paper: str, figures: Callable[[Any, ComposedScenario, Any], list] | str
) -> None:
    """``formation-ftc run --plot`` of a scenario with ``[scenario] paper = paper`` draws these figures
    (the paper's own figure set) instead of the generic error and command plots. ``figures`` may be a
    ``"module:attribute"`` reference, imported when a run draws them."""
    _PAPER_FIGURES[paper] = figures


def _plot(ds, scenario, out_dir):
    from formation_ftc.plotting import new_figure, save_figure

    paper = scenario.scenario.paper
    if paper in _PAPER_FIGURES:
        return resolve_reference(_PAPER_FIGURES[paper])(ds, scenario, out_dir)
    paths = []
    for var in ("position_error", "command"):
        if var not in ds:
            continue
        da = ds[var]
        fig, axes = new_figure(
            1, 1, title=f"{scenario.scenario.name}: {da.attrs.get('long_name', var)}"
        )
        ax = axes[0, 0]
        vals = np.linalg.norm(da.values, axis=-1) if "axis" in da.dims else da.values
        for k, sc in enumerate(ds.spacecraft.values):
            ax.plot(ds.time, vals[:, k], label=f"spacecraft {sc}")
        ax.set_xlabel("time [s]")
        ax.set_ylabel(f"|{var}| [{da.attrs.get('units', '')}]")
        ax.legend(loc="best")
        paths.append(save_figure(fig, out_dir / f"{var}.png"))
    return paths


METHOD = register_method(
    Method(
        name="composed",
        schema=ComposedScenario,
        build=build,
        check=check,
        plot=_plot,
        description="any law on any compatible plant with any fault (component catalog)",
    )
)
