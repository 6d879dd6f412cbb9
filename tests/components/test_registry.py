"""The component catalog (``formation_ftc.components._registry``): one home per type, found from its
path; a section's fields are its component's fields (the TOML path is the pytree path) or builder
inputs; a new type registered from one module of its own runs in a scenario; compatibility is decided
by ``ClosedLoop.validate`` from the parts' ``needs()`` / ``provides()``."""

from __future__ import annotations

import dataclasses
import importlib
import sys
import textwrap

import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components import _registry
from formation_ftc.components._registry import (
    KIND_PACKAGES,
    component_type,
    component_types,
    home_module,
    is_builder_input,
)
from formation_ftc.config import loader
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import CompositionError


def test_a_type_is_found_from_its_path_alone():
    entry = component_type("controller", "lqr")
    assert entry is not None and entry.module == home_module("controller", "lqr")
    assert entry.module == "formation_ftc.components.controllers.lqr"
    # names that are not type names never name a module to import
    for bad in ("LQR", "lqr_formation", "../lqr", "controllers.lqr", "", "_registry"):
        assert component_type("controller", bad) is None, bad


def test_every_registered_home_is_the_module_its_type_names():
    """A built-in type is registered by its home and nowhere else (one home per type)."""
    for (kind, name), entry in component_types().items():
        if entry.module.startswith("formation_ftc.components."):
            assert entry.module == home_module(kind, name), (kind, name)


def test_a_built_in_module_may_not_register_another_type():
    namespace = {"__name__": "formation_ftc.components.controllers.lqr"}
    code = "from formation_ftc.components._registry import register\nregister('controller', 'pd', object, None, '')"
    with pytest.raises(ValueError, match="one module per component type"):
        exec(code, namespace)  # noqa: S102 - a literal, to fake the calling module's name


def _component_fields(comp) -> set[str]:
    """Field names of a component and of the components it holds one level down."""
    names = {f.name for f in dataclasses.fields(comp)}
    for f in dataclasses.fields(comp):
        inner = getattr(comp, f.name)
        if dataclasses.is_dataclass(inner) and not isinstance(inner, type):
            names |= {g.name for g in dataclasses.fields(inner)}
    return names


def _built_in_loops():
    """(scenario, loop) of every built-in scenario."""
    for name in ftc.list_scenarios():
        scenario = ftc.load_scenario(name)
        yield scenario, make_loop(scenario)


@pytest.fixture(scope="module")
def loops():
    return list(_built_in_loops())


def test_section_fields_are_component_fields_or_builder_inputs(loops):
    """The TOML path is the pytree path: every field of a home's section is a field of the component
    it builds (of the same name) or a declared builder input. No renames."""
    seen = set()
    for scenario, loop in loops:
        for slot, name in scenario.labels().items():
            if slot.startswith("evaluations"):
                continue
            entry = component_type(slot, name)
            if entry is None or entry.module != home_module(slot, name) or (slot, name) in seen:
                continue
            seen.add((slot, name))
            fields = _component_fields(getattr(loop, slot))
            for field_name, info in entry.section.model_fields.items():
                assert is_builder_input(info) or field_name in fields, (
                    f"{slot} {name}: section field {field_name!r} is neither a field of "
                    f"{type(getattr(loop, slot)).__name__} nor a builder_input"
                )
    assert ("controller", "lqr") in seen


def test_no_section_renames_a_leaf():
    """No section declares ``leaf_paths`` (a field named otherwise in its component) any more."""
    for (kind, name), entry in component_types().items():
        if entry.module == home_module(kind, name):
            assert not hasattr(entry.section, "leaf_paths"), (kind, name)


_PLUGIN = '''
"""A proportional law on the measured position, registered from this one module."""
import jax.numpy as jnp
from pydantic import Field

from formation_ftc.components._registry import register
from formation_ftc.components.controllers._desired_position import DesiredPositionLaw
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import component
from formation_ftc.sim.contract import as_float


@component
class SpringLaw(DesiredPositionLaw):
    stiffness: object = 0.0  # [N/m]

    def output(self, t, state, inputs):
        return -self.stiffness * (inputs.measurement[:, :3] - inputs.exogenous["p"]), None, {}


class SpringSection(StrictModel):
    stiffness: float = Field(gt=0, description="Spring stiffness [N/m].")


def build(sec, ctx):
    return SpringLaw(count=ctx.count, stiffness=as_float(sec.stiffness))


register("controller", "test-spring", SpringSection, build, "a spring to the desired position")
'''


def test_a_new_type_is_one_module(tmp_path, monkeypatch):
    """A law written in one module of its own (as a plug-in would be) is registered when imported
    and runs in a scenario: the command equals its formula on the recorded states."""
    (tmp_path / "spring_plugin.py").write_text(textwrap.dedent(_PLUGIN))
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.import_module("spring_plugin")
    try:
        raw = {
            "scenario": {"name": "spring", "method": "composed"},
            "simulation": {"horizon": 2.0, "dt": 0.1, "record_every": 1},
            "plant": {
                "type": "clohessy-wiltshire",
                "semi_major_axis": 7000e3,
                "mass": [100.0],
                "initial_position": [[3.0, -2.0, 1.0]],
            },
            "controller": {"type": "test-spring", "stiffness": 0.5},
        }
        ds = ftc.simulate(loader.validate(raw, "spring"))
        expected = -0.5 * ds["position"].values
        np.testing.assert_allclose(ds["command"].values, expected, rtol=1e-12, atol=1e-12)
        bad = {**raw, "controller": {"type": "test-spring", "stiffness": -1.0}}
        with pytest.raises(loader.ScenarioError, match="controller.stiffness"):
            loader.validate(bad, "spring")
    finally:
        _registry._TYPES.pop(("controller", "test-spring"), None)
        sys.modules.pop("spring_plugin", None)


def test_validate_names_both_parts_of_an_unmet_need(loops):
    """A part that needs a capability no other part provides is refused by ``ClosedLoop.validate``,
    the message naming the part, the capability and who would provide it."""
    from formation_ftc.sim.contract import CAPABILITIES

    _, loop = next((s, lp) for s, lp in loops if s.scenario.name == "cw-pd-fault")
    assert "reference-orbit" in CAPABILITIES

    class Needy(type(loop.controller)):
        def needs(self):
            return {"reference-orbit": "design its gain on the reference orbit"}

    needy = Needy.__new__(Needy)
    for f in dataclasses.fields(loop.controller):
        object.__setattr__(needy, f.name, getattr(loop.controller, f.name))
    bad = dataclasses.replace(loop, controller=needy)
    with pytest.raises(
        CompositionError, match=r"controller pd needs a reference orbit known on board"
    ):
        bad.validate({"controller": "pd"})


def test_kind_packages_exist():
    for package in KIND_PACKAGES.values():
        importlib.import_module(f"formation_ftc.components.{package}")
