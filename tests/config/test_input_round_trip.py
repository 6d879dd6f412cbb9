"""Bad input is refused before any computation, naming the field (issue 34, items 3): nan/inf in every
list-valued numeric field of every built-in scenario, laws without an input they need; and every
built-in scenario round-trips through ``load_scenario`` and the resolved TOML of ``formation-ftc show``."""

from __future__ import annotations

import copy
import typing
from collections.abc import Iterator
from typing import Any

import pytest
from pydantic import BaseModel, ValidationError

from formation_ftc.api import list_scenarios, load_scenario
from formation_ftc.cli import _annotate_toml
from formation_ftc.config import loader
from formation_ftc.config.base import error_location
from formation_ftc.config.loader import ScenarioError
from formation_ftc.methods.composed import component_types
from formation_ftc.registry import get_method

SCENARIOS = sorted(list_scenarios())


def _numeric_list_items(node: Any, path: tuple = ()) -> Iterator[tuple]:
    """Path of the first number of every list of numbers (nested lists included) inside ``node``."""
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _numeric_list_items(v, (*path, k))
    elif isinstance(node, list):
        if any(isinstance(x, dict) for x in node):  # an array of tables: look inside each table
            for k, v in enumerate(node):
                yield from _numeric_list_items(v, (*path, k))
            return
        inner: tuple = ()
        item: Any = node
        while isinstance(item, list) and item:
            inner, item = (*inner, 0), item[0]
        if isinstance(item, int | float) and not isinstance(item, bool):
            yield (*path, *inner)


def _location(path: tuple) -> str:
    """``("actuator", "magnitude", 1, 2)`` -> ``actuator.magnitude[1][2]``."""
    return "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in path).lstrip(".")


def _set(raw: dict, path: tuple, value: Any) -> None:
    node = raw
    for p in path[:-1]:
        node = node[p]
    node[path[-1]] = value


CASES = [
    (name, path, float("nan") if k % 2 else float("-inf"))
    for k, (name, path) in enumerate(
        (name, path) for name in SCENARIOS for path in _numeric_list_items(loader.read_raw(name)[0])
    )
]


def test_the_sweep_covers_the_composed_catalog_lists():
    covered = {(name, _location(p)) for name, p, _ in CASES}
    for expected in [
        ("compose-li2020-on-cw", "actuator.magnitude[0]"),
        ("compose-li2020-on-cw", "plant.mass[0]"),
        ("compose-li2020-on-cw", "network.adjacency[0][0]"),
        ("cw-pd-fault", "plant.mass[0]"),
    ]:
        assert expected in covered
    assert len(CASES) > 50


@pytest.mark.parametrize(
    "name, path, value", CASES, ids=[f"{n}:{_location(p)}={v}" for n, p, v in CASES]
)
def test_nan_and_inf_in_list_fields_are_refused_naming_the_item(name, path, value):
    raw = loader.read_raw(name)[0]
    _set(raw, path, value)
    with pytest.raises(ScenarioError) as err:
        load_scenario(raw)
    message = str(err.value)
    assert _location(path) in message, message
    assert "finite" in message, message


def _models(model: type[BaseModel]) -> Iterator[type[BaseModel]]:
    """``model`` and the models nested in its fields."""
    yield model
    stack = [f.annotation for f in model.model_fields.values()]
    while stack:
        a = stack.pop()
        if isinstance(a, type) and issubclass(a, BaseModel):
            yield from _models(a)
        else:
            stack.extend(typing.get_args(a))


def _takes(annotation: Any, kind: type) -> bool:
    """Whether ``annotation`` admits ``kind`` (float) or a container of that origin (list, tuple)."""
    if annotation is kind or typing.get_origin(annotation) is kind:
        return True
    return any(_takes(a, kind) for a in typing.get_args(annotation))


CATALOG_FIELDS = sorted(
    {
        (f"{kind}.{name}", model, field)
        for (kind, name), entry in component_types().items()
        for model in _models(entry.section)
        for field, info in model.model_fields.items()
        if _takes(info.annotation, float)
        and (_takes(info.annotation, list) or _takes(info.annotation, tuple))
    },
    key=lambda c: (c[0], c[1].__name__, c[2]),
)


@pytest.mark.parametrize(
    "where, model, field",
    CATALOG_FIELDS,
    ids=[f"{w}:{m.__name__}.{f}" for w, m, f in CATALOG_FIELDS],
)
def test_every_list_field_of_the_composed_catalog_refuses_nan_and_inf(where, model, field):
    for bad in (float("nan"), float("inf")):
        with pytest.raises(ValidationError) as err:
            model.model_validate({field: [1.0, [2.0, bad]]})
        assert any(
            error_location(e) == f"{field}[1][1]" and "finite" in e["msg"]
            for e in err.value.errors()
        ), err.value


def test_thruster_bias_per_spacecraft_rows_name_field_index_and_range():
    raw = loader.read_raw("compose-li2020-on-cw")[0]
    raw["actuator"]["magnitude"] = [[0.5, 0.0, 0.0], [0.0, 0.0, float("nan")], [0.0] * 3, [0.0] * 3]
    with pytest.raises(
        ScenarioError,
        match=r"actuator\.magnitude\[1\]\[2\]: nan is refused: must be a finite "
        r"number",
    ):
        load_scenario(raw)


@pytest.mark.parametrize(
    "name, drop, slot_type",
    [
        ("compose-li2020-on-cw", "reference", "controller li2020-adaptive"),
        ("compose-gui2022-on-li2020", "estimator", "controller gui2022-lof2tc"),
    ],
)
def test_a_law_missing_an_input_it_needs_is_refused_naming_both_parts(name, drop, slot_type):
    raw = loader.read_raw(name)[0]
    del raw[drop]
    raw["metrics"] = [m for m in raw.get("metrics", []) if m["signal"] not in ("fault_error",)]
    with pytest.raises(ScenarioError) as err:
        load_scenario(raw)
    # the part that needs it, and who would provide it (ClosedLoop.validate's message)
    assert slot_type in str(err.value) and "no part of this loop provides it" in str(err.value)
    assert {"reference": "[reference] section", "estimator": 'estimator type = "'}[drop] in str(
        err.value
    )


def test_cof2tc_compensation_without_an_estimator_is_refused():
    raw = loader.read_raw("compose-gui2022-on-li2020")[0]
    del raw["estimator"]
    raw["metrics"] = []
    law = {
        k: v
        for k, v in raw["controller"].items()
        if k not in ("G1", "G2", "G3", "G4", "pi_initial", "v_initial", "learning_interval")
    }
    raw["controller"] = {**law, "type": "gui2022-cof2tc", "fault_compensation": True}
    with pytest.raises(
        ScenarioError,
        match=r"controller gui2022-cof2tc needs .* \(fault_compensation = true\), but no part of "
        r"this loop provides it \(provided by: estimator type = \"iterative-learning-observer\"\)",
    ):
        load_scenario(raw)
    raw["controller"]["fault_compensation"] = False  # the plain baseline needs no estimate
    load_scenario(raw)


def test_the_cli_refuses_a_law_without_its_reference_with_exit_2(tmp_path, capsys):
    import tomli_w

    from formation_ftc.cli import main

    raw = loader.read_raw("compose-li2020-on-cw")[0]
    del raw["reference"]
    path = tmp_path / "noref.toml"
    path.write_text(tomli_w.dumps(raw))
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert "controller li2020-adaptive" in err and "[reference]" in err


@pytest.mark.parametrize("name", SCENARIOS)
def test_every_builtin_scenario_round_trips(name):
    scn = load_scenario(name)
    again = load_scenario(scn)
    assert again == scn
    text = loader.dump_toml(scn)
    assert load_scenario(loader.parse_toml(text, "<dump>")) == scn
    shown = _annotate_toml(
        text, get_method(scn.scenario.method).schema.model_json_schema()
    )  # `show`
    assert load_scenario(loader.parse_toml(shown, "<show>")) == scn
    assert load_scenario(copy.deepcopy(again)) == scn
