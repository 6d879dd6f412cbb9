"""Conformance of every built-in scenario and every catalog component type (issue 35 item 2: flight
knowledge is stated, never copied from truth).

Sources: every built-in scenario (``api.list_scenarios()``), one cell of every method file of the
built-in leagues (``league/data``) and two small compositions for the catalog types no built-in uses
(``pd`` with ``expression-faults``, and the Gui2022 learning laws on a CW plant without a reference
orbit). Checks:

(a) *truth-blindness*: perturbing truth fields -- the plant's masses, inertias, initial state and
    orbit, the true fault parameters (actuator), the disturbance -- leaves every array leaf and the
    structure of the flight components (controller, estimator, supervisor) bit-identical, with the
    flight knowledge as the scenario states it and with every stated knowledge field left out (its
    documented nominal default then applies); and the flight components' methods take
    :class:`~formation_ftc.sim.components.FlightInputs` only;
(b) *declared signals equal outputs*: a short run records exactly the declared signals, with their
    dims, and the dataset holds them;
(c) *pytree round trip*: unflattening a loop's leaves gives the loop back;
(d) *TOML round trip*: a scenario re-validated and its dumped TOML loaded again build the same loop.

Truth and flight: a composed ``[reference]`` is the reference orbit, a mission definition known on
board, so it is not perturbed; a plant's own orbit fields (a CW plant's ``semi_major_axis`` or
``mean_motion``) are truth. Two estimators are scripted
reports of the true faults by design (their model *is* an FDI outcome as a function of the fault):
:class:`~formation_ftc.components.estimators.scripted_fdi.ScriptedFdi` and
:class:`~formation_ftc.components.estimators.scheduled_diagnosis.ScheduledDiagnosis`; they are exempt
from the fault perturbations only (see ``FAULT_ORACLES``).
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import inspect
import math
import re
import tomllib
from collections.abc import Callable
from typing import Any

import jax
import numpy as np
import pytest

from formation_ftc import api
from formation_ftc.config import loader
from formation_ftc.methods.composed import component_types
from formation_ftc.sim import components as contract
from formation_ftc.sim.components import FlightInputs, structure_key
from formation_ftc.sim.loop import ClosedLoop

FLIGHT_SLOTS = ("controller", "estimator", "supervisor")
FLIGHT_KINDS = (contract.Controller, contract.Estimator, contract.Supervisor)
#: methods of a flight component that receive the loop's inputs
FLIGHT_METHODS = ("update", "output", "message", "step")
TRUTH_INPUTS = (
    contract.TruthInputs,
    contract.ActuatorInputs,
    contract.SensorInputs,
    contract.NetworkInputs,
)

#: estimators that model an FDI's report as a function of the true faults (scripted by design): exempt
#: from the fault perturbations only
FAULT_ORACLES = {
    "ScriptedFdi": "scripted FDI report (flag, u*) of the actuator's faults with imperfections",
    "ScheduledDiagnosis": "diagnosis at the true onset plus the stated diagnosis delay (Yang2013)",
}

# ------------------------------------------------------------------------------------------ sources
MASS4 = [100.0, 120.0, 115.0, 108.0]
_CW_PLANT = {
    "type": "clohessy-wiltshire",
    "semi_major_axis": 7000e3,
    "mass": MASS4,
    "initial_position": [
        [250.0, 20.0, 423.0],
        [-15.0, -505.0, 10.0],
        [-238.0, -10.0, -433.0],
        [5.0, 500.0, 15.0],
    ],
    "disturbance_force": ["1e-3*sin(0.01*t + i)", "0", "1e-3*cos(0.01*t)"],
}


def _synthetic_learning_on_cw() -> dict:
    """The Gui2022 ILO and COF2TC (with fault compensation) on a CW plant with no [reference]: their CW
    model's mean motion is stated (the default would come from the plant)."""
    base = loader.read_raw("compose-gui2022-on-li2020")[0]
    n = math.sqrt(3.986004418e14 / 7000e3**3)
    ctl = {
        k: v
        for k, v in base["controller"].items()
        if k in ("desired_state", "K", "nominal_mass", "gains")
    }
    return {
        "scenario": {"name": "synthetic-learning-on-cw", "method": "composed"},
        "simulation": {"horizon": 0.004, "dt": 0.001, "record_every": 2},
        "plant": copy.deepcopy(_CW_PLANT),
        "sensors": {"type": "relative-state"},
        "estimator": {**base["estimator"], "mean_motion": n},
        "controller": {
            **ctl,
            "type": "gui2022-cof2tc",
            "fault_compensation": True,
            "mean_motion": n,
        },
        "actuator": copy.deepcopy(base["actuator"]),
    }


def _synthetic_step_faults() -> dict:
    """``step-faults`` (the numeric profile of the li2020 campaign, no built-in scenario uses it) on
    li2020-thm1."""
    raw = loader.read_raw("li2020-thm1")[0]
    raw["simulation"] = {"horizon": 0.2, "dt": 0.01, "record_every": 5}
    raw["actuator"] = {
        "type": "step-faults",
        "effectiveness": [[0.5, 1.0, 1.0], [1.0, 0.6, 1.0], [1.0, 1.0, 0.7], [0.4, 0.4, 0.4]],
        "onset": [[0.1, 0.0, 0.0], [0.0, 0.15, 0.0], [0.0, 0.0, 0.2], [0.05, 0.05, 0.05]],
        "bias": raw["actuator"]["bias"],
    }
    return raw


SYNTHETIC: dict[str, Callable[[], dict]] = {
    "synthetic:learning-on-cw": _synthetic_learning_on_cw,
    "synthetic:step-faults": _synthetic_step_faults,
}


def _league_keys() -> list[str]:
    from formation_ftc.league.definition import builtin_leagues, load_league

    return [
        f"league:{name}:{m.name}"
        for name in sorted(builtin_leagues())
        for m in load_league(name).methods
    ]


@functools.cache
def source_raw(key: str) -> dict:
    """The raw scenario dict of a source (a fresh copy must be taken before changing it)."""
    if key in SYNTHETIC:
        return SYNTHETIC[key]()
    if key.startswith("league:"):
        from formation_ftc.league.definition import load_league, method_scenario
        from formation_ftc.league.runner import _battery, _network_kind

        _, league, method = key.split(":")
        spec = load_league(league)
        entry = spec.method(method)
        network, delayed = _network_kind(spec, entry)
        # the first actuator case that applies (a fault on the truth side), the league's first level
        case = next(
            c
            for c in _battery(spec).cases
            if c.applies_to(network=network, delayed=delayed) and not c.communication
        )
        quantity = "torque" if spec.league.kind == "attitude" else "force"
        level = spec.levels[0]
        return method_scenario(
            spec,
            entry,
            level,
            case.actuator_fields(saturation=level.saturation, quantity=quantity),
            case.network_fields(delayed=delayed) if network else None,
        )
    return loader.read_raw(key)[0]


SOURCES = sorted(api.list_scenarios()) + _league_keys() + list(SYNTHETIC)


def build(raw: dict, overrides: dict | None = None) -> ClosedLoop:
    loop = api.build_loop(api.load_scenario(copy.deepcopy(raw), overrides=overrides))
    assert isinstance(loop, ClosedLoop)
    return loop


@functools.cache
def base_loop(key: str) -> ClosedLoop:
    return build(source_raw(key))


def type_of(raw: dict, slot: str) -> str | None:
    section = raw.get(slot)
    return None if section is None else section.get("type")


# -------------------------------------------------------------------------------- flight knowledge
#: the knowledge fields of each flight type of the catalog: left out, each takes its documented nominal
#: default (a constant, or the [reference] orbit known on board), never a truth value
KNOWLEDGE: dict[tuple[str, str], tuple[str, ...]] = {
    ("controller", "pd"): ("nominal_mass",),
    ("controller", "none"): (),
    ("controller", "lqr"): (
        "nominal_mass",
        "mu",
    ),  # semi_major_axis: the [reference]'s, required without one
    ("controller", "azizi2009-llfr"): ("nominal_mass", "b", "b_hat"),
    ("controller", "yang2013-translational"): ("nominal_mass",),
    ("controller", "yang2013-relative"): ("nominal_mass",),
    ("controller", "networked-el-hinf"): ("nominal_inertia",),
    ("controller", "yang2013-attitude"): ("nominal_inertia",),
    ("controller", "attitude-pd"): (),
    ("controller", "li2020-adaptive"): ("m_hat0", "orbit_mu"),
    ("controller", "sir-ftc"): ("b_hat0",),
    ("controller", "gui2022-lof2tc"): ("nominal_mass", "mean_motion"),
    ("controller", "gui2022-cof2tc"): ("nominal_mass", "mean_motion"),
    ("estimator", "iterative-learning-observer"): (
        "nominal_mass",
        "mean_motion",
        "initial_estimate",
    ),
    ("estimator", "scripted-fdi"): (),
    ("estimator", "relative-navigation-filter"): ("nominal_mass", "mu", "acceleration_noise_psd"),
    ("estimator", "residual-fdi"): ("nominal_mass", "mu", "acceleration_noise_psd"),
    ("estimator", "attitude-residual-fdi"): (
        "nominal_inertia",
        "semi_major_axis",
        "mu",
        "torque_limit",
    ),
    ("supervisor", "hierarchical"): (),
    ("controller", "yang2013-force-torque"): ("nominal_mass", "nominal_inertia"),
    ("estimator", "scheduled-diagnosis"): (),
    ("supervisor", "switching"): (),
}


def without_knowledge(raw: dict) -> dict | None:
    """``raw`` with every stated knowledge field of its flight components left out (None: nothing to
    leave out)."""
    out = copy.deepcopy(raw)
    dropped = False
    for slot in FLIGHT_SLOTS:
        section = out.get(slot)
        if section is None:
            continue
        for name in KNOWLEDGE[(slot, section["type"])]:
            dropped |= section.pop(name, None) is not None
    return out if dropped else None


def _dropped(raw: dict) -> set[str]:
    """Names of the knowledge fields :func:`without_knowledge` leaves out of ``raw``."""
    out = set()
    for slot in FLIGHT_SLOTS:
        section = raw.get(slot) or {}
        out |= {
            name for name in KNOWLEDGE.get((slot, section.get("type", "")), ()) if name in section
        }
    return out


def test_every_flight_type_declares_its_knowledge():
    """A new flight component type must say which of its fields are flight knowledge (KNOWLEDGE), and
    those must be fields of its section."""
    for (kind, name), entry in component_types().items():
        if kind not in FLIGHT_SLOTS:
            continue
        assert (kind, name) in KNOWLEDGE, f"{kind} {name}: add its knowledge fields to KNOWLEDGE"
        for field in KNOWLEDGE[(kind, name)]:
            assert field in entry.section.model_fields, (kind, name, field)


#: catalog types no built-in scenario or league uses: covered by the synthetic sources only
UNUSED_BY_BUILTINS = {("actuator", "step-faults")}


def _types_used(keys) -> set[tuple[str, str]]:
    used = set()
    for key in keys:
        raw = source_raw(key)
        used |= {
            (slot, str(type_of(raw, slot)))
            for slot in (
                "plant",
                "reference",
                "sensors",
                "network",
                "estimator",
                "supervisor",
                "controller",
                "actuator",
            )
            if type_of(raw, slot)
        }
        used |= {("evaluation", e["type"]) for e in raw.get("evaluations", [])}
    return used


def test_every_catalog_type_is_used_by_a_source():
    types = set(component_types())
    assert types <= _types_used(SOURCES), sorted(types - _types_used(SOURCES))
    builtin = _types_used([k for k in SOURCES if k not in SYNTHETIC])
    assert types - builtin == UNUSED_BY_BUILTINS


# -------------------------------------------------------------------------------- truth perturbations
def _scale(v, f: float, add: float = 0.0):
    if isinstance(v, list | tuple):
        return [_scale(x, f, add) for x in v]
    return v * f + add


def _expr(v, f: str = "1.1"):
    if isinstance(v, list | tuple):
        return [_expr(x, f) for x in v]
    return v if str(v).strip() == "0" else f"{f}*({v})"


def _expr_bias(v):
    return [f"({x}) + 0.001" for x in v] if isinstance(v, list | tuple) else f"({v}) + 0.001"


#: composed plant fields by kind of truth -> perturbation
PLANT_TRUTH: dict[str, dict[str, Callable[[Any], Any]]] = {
    "mass": {"mass": lambda v: _scale(v, 1.1)},
    "inertia": {
        "inertia": lambda v: _scale(v, 1.1),
        "inertia_matrices": lambda v: _scale(v, 1.1),
        "inertia_uncertainty": lambda v: v * 0.5,
    },
    "initial_state": {
        "initial_position": lambda v: _scale(v, 1.0, 1.0),
        "initial_velocity": lambda v: _scale(v, 1.0, 0.01),
        "initial_roe": lambda v: _scale(v, 1.0, 1.0),
        "initial_attitude_deg": lambda v: _scale(v, 1.0, 2.0),
        "initial_body_rate": lambda v: _scale(v, 1.0, 0.001),
        "initial_attitude_range_deg": lambda v: _scale(v, 0.8, 5.0),
        "initial_rate_deg_s": lambda v: _scale(v, 1.0, 0.1),
        "initial_position_std": lambda v: v + 1.0,
        "dispersion_seed": lambda v: v + 1,
        "initial_state": lambda v: [
            {**s, "e_R": _scale(list(s.get("e_R", [0.0] * 3)), 1.0, 0.1)} for s in v
        ],
    },
    "disturbance": {
        "disturbance_force": _expr,
        "disturbance_torque": _expr,
        "disturbance_acceleration": _expr,
        "disturbance_amplitude": lambda v: v * 1.5 + 1e-6,
        "process_noise_std": lambda v: v + 1e-4,
        "disturbance_variance": lambda v: v * 2 + 1e-4,
        "ballistic_coefficient": lambda v: _scale(v, 1.1),
        "srp_coefficient": lambda v: _scale(v, 1.1, 0.001),
    },
    "orbit": {
        "semi_major_axis": lambda v: v * 1.001,
        "mean_motion": lambda v: v * 1.001,
        "eccentricity": lambda v: v + 0.001,
        "mu": lambda v: v * 1.0001,
    },
}
#: composed actuator fields (true faults, limits) -> perturbation
ACTUATOR_TRUTH: dict[str, Callable[[Any], Any]] = {
    "onset": lambda v: _scale(v, 1.0, 1.0),
    "effectiveness": lambda v: (
        _expr(v, "0.9") if isinstance(v, list) and isinstance(v[0], str) else _scale(v, 0.9)
    ),
    "bias": lambda v: (
        _expr_bias(v) if isinstance(v, list) and isinstance(v[0], str) else _scale(v, 1.1, 0.001)
    ),
    "gain": lambda v: _scale(v, 1.1),
    "magnitude": lambda v: _scale(v, 1.1, 0.001),
    "amplitude": lambda v: _scale(v, 1.1, 0.001),
    "decay_amplitude": lambda v: _scale(v, 1.1, 0.001),
    "omega": lambda v: _scale(v, 1.0, 0.001),
    "phase": lambda v: _scale(v, 1.0, 0.01),
    "decay_rate": lambda v: _scale(v, 1.0, 0.001),
    "saturation": lambda v: _scale(v, 1.1),
    "rate": lambda v: v + 0.001,
    "period": lambda v: v + 1.0,
    "duty": lambda v: v * 0.9,
    "min_effectiveness": lambda v: v * 0.9 + 0.01,
    "faults": lambda v: [
        {**f, "torque": _expr(f["torque"]), "start": f["start"] + 1.0, "end": f["end"] + 1.0}
        if "torque" in f
        else {**f, "K2_faulty": f["K2_faulty"] * 1.5, "onset": f["onset"] + 1.0}  # velocity gain
        for f in v
    ],
}


def _composed_truth(raw: dict) -> dict[str, dict]:
    out: dict[str, dict] = {}
    plant = raw["plant"]
    for kind, fields in PLANT_TRUTH.items():
        ov = {f"plant.{k}": fn(plant[k]) for k, fn in fields.items() if k in plant}
        if ov:
            out[kind] = ov
    actuator = raw.get("actuator") or {}
    ov = {f"actuator.{k}": fn(actuator[k]) for k, fn in ACTUATOR_TRUTH.items() if k in actuator}
    if ov:
        out["fault"] = ov
    return out


def truth_perturbations(raw: dict) -> dict[str, dict]:
    return _composed_truth(raw)


# ------------------------------------------------------------- known truth copies in two catalog files


# ------------------------------------------------------------------------------ (a) truth-blindness
def flight_view(loop: ClosedLoop) -> dict[str, Any]:
    return {slot: getattr(loop, slot) for slot in FLIGHT_SLOTS}


def differing_leaves(a, b) -> list[str]:
    """Paths of the leaves of ``a`` and ``b`` that are not bit-identical (same dtype and shape)."""
    la, _ = jax.tree_util.tree_flatten_with_path(a)
    lb, _ = jax.tree_util.tree_flatten_with_path(b)
    out = []
    for (path, x), (_, y) in zip(la, lb, strict=True):
        x, y = np.asarray(x), np.asarray(y)
        if (
            x.dtype != y.dtype
            or x.shape != y.shape
            or not np.array_equal(x, y, equal_nan=x.dtype.kind == "f")
        ):
            out.append(jax.tree_util.keystr(path))
    return out


def _cases():
    for key in SOURCES:
        raw = source_raw(key)
        variants = {"stated": raw}
        defaults = without_knowledge(raw)
        if defaults is not None:
            variants["defaults"] = defaults
        for variant, vraw in variants.items():
            for kind in truth_perturbations(vraw):
                yield pytest.param(key, variant, kind, id=f"{key}-{variant}-{kind}")


@functools.cache
def _variant_raw(key: str, variant: str) -> dict:
    raw = source_raw(key)
    if variant == "stated":
        return raw
    out = without_knowledge(raw)
    assert out is not None
    return out


@functools.cache
def _variant_loop(key: str, variant: str) -> ClosedLoop:
    return build(_variant_raw(key, variant))


@pytest.mark.parametrize(("key", "variant", "kind"), list(_cases()))
def test_flight_components_are_blind_to_truth(key, variant, kind):
    raw = _variant_raw(key, variant)
    overrides = truth_perturbations(raw)[kind]
    try:
        ref = _variant_loop(key, variant)
    except loader.ScenarioError as exc:
        dropped = _dropped(source_raw(key))
        if variant == "defaults" and any(name in str(exc) for name in dropped):
            return  # the knowledge has no default: a scenario must state it (nothing is copied from truth)
        raise
    moved = build(raw, overrides)
    # the perturbation reaches the truth side (else the test proves nothing)
    truth = (moved.plant, moved.actuator)
    assert differing_leaves((ref.plant, ref.actuator), truth) or structure_key(
        (ref.plant, ref.actuator)
    ) != structure_key(truth), f"{kind}: {overrides} changes no truth"
    for slot, comp in flight_view(ref).items():
        other = getattr(moved, slot)
        if kind == "fault" and type(comp).__name__ in FAULT_ORACLES:
            continue
        assert structure_key(comp) == structure_key(other), (
            f"{slot} {type(comp).__name__}: structure changed with truth {kind} ({overrides})"
        )
        diff = differing_leaves(comp, other)
        assert not diff, (
            f"{slot} {type(comp).__name__}: leaves {diff} moved with truth {kind} ({overrides})"
        )


def _flight_components(loop: ClosedLoop):
    """Every flight component of the loop, nested ones (a wrapped law, an inner estimator) included."""
    seen: list = []

    def walk(obj):
        if isinstance(obj, FLIGHT_KINDS):
            seen.append(obj)
        if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
            for f in dataclasses.fields(obj):
                walk(getattr(obj, f.name))
        elif isinstance(obj, tuple | list):
            for x in obj:
                walk(x)

    for slot in FLIGHT_SLOTS:
        walk(getattr(loop, slot))
    return seen


def _hints(fn) -> dict[str, Any]:
    """Type hints of ``fn``: resolved objects where they resolve (in the contract's and the function's
    module namespaces), else the annotation text."""
    module = inspect.getmodule(fn)
    namespace = {**vars(contract), **(vars(module) if module else {})}
    out: dict[str, Any] = {}
    for name, ann in getattr(fn, "__annotations__", {}).items():
        try:
            out[name] = eval(ann, namespace) if isinstance(ann, str) else ann  # noqa: S307 - annotation text
        except Exception:  # noqa: BLE001 - a name only imported for type checkers: keep the text
            out[name] = ann
    return out


def _name(hint: Any) -> str:
    return str(getattr(hint, "__name__", hint))


@pytest.mark.parametrize("key", SOURCES)
def test_flight_components_take_flight_inputs_only(key):
    truth_types = {t.__name__ for t in TRUTH_INPUTS}
    for comp in _flight_components(base_loop(key)):
        cls = type(comp)
        checked = 0
        for name, fn in inspect.getmembers(cls, inspect.isfunction):
            hints = _hints(fn)
            for param, hint in hints.items():
                assert not re.search(rf"\b({'|'.join(truth_types)})\b", _name(hint)), (
                    f"{cls.__name__}.{name}({param}): a truth-side input type {hint}"
                )
            if name in FLIGHT_METHODS and "inputs" in inspect.signature(fn).parameters:
                assert hints.get("inputs") is FlightInputs, (
                    f"{cls.__name__}.{name}: inputs is {hints.get('inputs')}"
                )
                checked += 1
        assert checked, f"{cls.__name__}: no method takes FlightInputs"
    assert not {"state", "fault", "disturbance", "force"} & set(FlightInputs._fields)


# ----------------------------------------------------------------- (b) declared signals equal outputs
def _short(raw: dict) -> dict:
    """``raw`` cut to 4 steps, recorded every 2."""
    scn = api.load_scenario(copy.deepcopy(raw))
    return api.load_scenario(
        scn, overrides={"simulation.horizon": 4 * scn.simulation.dt, "simulation.record_every": 2}
    )


def _check_records(loop: ClosedLoop, records: dict[str, Any]) -> None:
    """The records of a run of ``loop`` (arrays or shape structs) are exactly its declared signals."""
    declared = loop.signals()
    names = [s.name for s in declared]
    assert len(names) == len(set(names)), (
        f"signals declared twice: {sorted({n for n in names if names.count(n) > 1})}"
    )
    assert set(records) == set(names), (
        f"recorded but not declared: {sorted(set(records) - set(names))}; "
        f"declared but not recorded: {sorted(set(names) - set(records))}"
    )
    n_rec = loop.n_steps // loop.record_every + 1
    for sig in declared:
        shape = tuple(np.shape(records[sig.name]))
        assert len(shape) == 1 + len(sig.dims), (
            f"{sig.name}: dims {sig.dims}, recorded shape {shape}"
        )
        assert shape[0] >= n_rec, f"{sig.name}: {shape[0]} records for {n_rec}"
        for dim, size in zip(sig.dims, shape[1:], strict=True):
            if dim == "spacecraft":
                assert size == loop.count, f"{sig.name}: {size} spacecraft for {loop.count}"


def _check_dataset(loop: ClosedLoop, ds, cf: bool) -> None:
    n_rec = loop.n_steps // loop.record_every + 1
    assert set(ds.data_vars) == {s.name for s in loop.signals()}
    for sig in loop.signals():
        var = ds[sig.name]
        assert var.dims == ("time", *sig.dims), (sig.name, var.dims, sig.dims)
        assert var.sizes["time"] == n_rec, sig.name
        units = var.attrs["units"]
        if (
            cf and "," in sig.units
        ):  # a stacked vector of mixed units: CF stores "1" and the components' units
            assert (units, var.attrs.get("component_units")) == ("1", sig.units), sig.name
        else:
            assert units == sig.units, (sig.name, units, sig.units)


@pytest.mark.parametrize("key", SOURCES)
def test_declared_signals_equal_the_recorded_outputs(key):
    """Every source, 4 steps recorded every 2: the run's records (traced, ``jax.eval_shape``: no
    compilation) are exactly the declared signals with their dims, and the dataset built from them holds
    each with its dims and units."""
    scn = _short(source_raw(key))
    compiled = api.build_loop(scn)
    loop = compiled
    shapes = jax.eval_shape(lambda p: dict(p.run()), loop)
    _check_records(loop, dict(shapes["records"]))
    n_rec = loop.n_steps // loop.record_every + 1
    zeros = {k: np.zeros(v.shape, v.dtype) for k, v in dict(shapes["records"]).items()}
    _check_dataset(loop, compiled.dataset({"records": zeros}, n_rec), cf=False)


#: run end to end (``simulate_with_metrics``, one compiled program each): CF units of mixed vectors
#: (gui2022's ILO estimate) and a plain translational loop
RUN_END_TO_END = ("cw-free-drift", "gui2022-ilo")


@pytest.mark.parametrize("key", RUN_END_TO_END)
def test_short_run_dataset_holds_the_declared_signals(key):
    scn = _short(source_raw(key))
    ds, metrics = api.simulate_with_metrics(scn, raise_on_divergence=False)
    loop = api.build_loop(scn)
    assert not ds.attrs["diverged"]
    _check_dataset(loop, ds, cf=True)
    assert set(metrics) >= {m.name for m in loop.metrics if m.spacecraft != "each"}


# ----------------------------------------------------------------------- (c) pytree round trip
@pytest.mark.parametrize("key", SOURCES)
def test_pytree_round_trip(key):
    loop = base_loop(key)
    leaves, treedef = jax.tree_util.tree_flatten(loop)
    again = jax.tree_util.tree_unflatten(treedef, leaves)
    assert type(again) is type(loop)
    assert structure_key(again) == structure_key(loop)
    leaves2 = jax.tree_util.tree_leaves(again)
    assert len(leaves2) == len(leaves) and all(a is b for a, b in zip(leaves, leaves2, strict=True))
    copied = jax.tree_util.tree_map(np.array, loop)  # new arrays, same numbers
    assert structure_key(copied) == structure_key(loop) and not differing_leaves(copied, loop)


# ----------------------------------------------------------------------- (d) TOML round trip
@pytest.mark.parametrize("key", SOURCES)
def test_toml_round_trip(key):
    scn = api.load_scenario(copy.deepcopy(source_raw(key)))
    loop = base_loop(key)
    again = api.load_scenario(scn)
    dumped = api.load_scenario(tomllib.loads(loader.dump_toml(scn)))
    for other in (again, dumped):
        rebuilt = api.build_loop(other)
        assert structure_key(rebuilt) == structure_key(loop)
        assert not differing_leaves(rebuilt, loop)
