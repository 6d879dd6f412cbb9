"""The catalog index (issue 37 item 2): validating a composed scenario imports only the catalog modules
of the types it names, so the index must name, for every built-in type, the module that registers it.

The import checks run in a fresh interpreter (this one has every catalog loaded by other tests)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from formation_ftc.methods.composed._catalog_index import CATALOG_INDEX

_PACKAGE = "formation_ftc.methods.composed"

# every register_component_type call, attributed to the module whose import (module body) made it
_REGISTRANTS = """
import json, sys
import formation_ftc.methods.composed as composed
early = sorted(m for m in sys.modules if ".catalog_" in m)
original = composed.register_component_type
calls = []
def record(kind, name, *args, **kwargs):
    frame = sys._getframe(1)
    while frame.f_code.co_name != "<module>":
        frame = frame.f_back
    calls.append([kind, name, frame.f_globals["__name__"]])
    return original(kind, name, *args, **kwargs)
composed.register_component_type = record
composed._load_catalogs()
print(json.dumps({"early": early, "calls": calls}))
"""


def _fresh(code: str) -> dict:
    """Run ``code`` in a fresh interpreter; its last stdout line, as JSON."""
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=600
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_index_names_the_module_that_registers_each_type():
    got = _fresh(_REGISTRANTS)
    assert got["early"] == [], "a catalog module was imported before the probe could record it"
    registrants = [((kind, name), module) for kind, name, module in got["calls"]]
    keys = [key for key, _ in registrants]
    assert len(keys) == len(set(keys)), "a type registered twice: loading order would matter"
    actual = dict(registrants)
    missing = sorted(set(actual) - set(CATALOG_INDEX))
    stale = sorted(set(CATALOG_INDEX) - set(actual))
    wrong = sorted(k for k in set(actual) & set(CATALOG_INDEX) if actual[k] != CATALOG_INDEX[k])
    assert not missing, f"add to methods/composed/_catalog_index.py: {missing}"
    assert not stale, f"no longer registered, remove from the index: {stale}"
    assert not wrong, f"registered by another module: {[(k, actual[k]) for k in wrong]}"


@pytest.mark.parametrize(
    ("paper", "kind", "name", "constant"),
    [
        ("azizi2009", "controller", "azizi2009-llfr", "catalog_chain:CHAIN_LAW"),
        ("gui2022", "estimator", "iterative-learning-observer", None),
        ("gui2022", "controller", "gui2022-lof2tc", None),
        ("gui2022", "controller", "gui2022-cof2tc", None),
        ("mehrabian", "controller", "networked-el-hinf", "catalog_attitude:EULER_LAW"),
        ("yang2013", "supervisor", "switching", None),
    ],
)
def test_paper_registrations_name_the_catalog_constants(paper, kind, name, constant):
    """The papers' registration modules name these types as text (no catalog import at start-up);
    ``constant`` None: a type with a home (found from its name)."""
    import importlib

    from formation_ftc.components._registry import home_module
    from formation_ftc.methods.composed import _CONDITIONS, component_type
    from formation_ftc.registry import load_plugins

    load_plugins()
    if constant is None:
        assert component_type(kind, name).module == home_module(kind, name)
    else:
        module, attr = constant.split(":")
        assert getattr(importlib.import_module(f"{_PACKAGE}.{module}"), attr) == name
        assert CATALOG_INDEX[(kind, name)] == f"{_PACKAGE}.{module}"
    refs = [f for f in _CONDITIONS.get((kind, name), []) if isinstance(f, str)]
    assert any(r.startswith(f"formation_ftc.papers.{paper}.") for r in refs), (kind, name, refs)


_VALIDATE = """
import json, sys
from formation_ftc.config import loader
raw, _ = loader.read_raw({scenario!r})
raw.update({extra!r})
try:
    loader.validate(raw, "<x>", build=False)
    error = None
except loader.ScenarioError as exc:
    error = str(exc)
from formation_ftc.methods.composed import _CATALOG
catalogs = sorted(m.rsplit(".", 1)[1] for m in sys.modules if ".catalog_" in m)
known = sorted(n for (k, n) in _CATALOG if k == "controller")
print(json.dumps({{"catalogs": catalogs, "error": error, "known": known}}))
"""


def test_validation_imports_only_the_named_catalogs():
    got = _fresh(_VALIDATE.format(scenario="cw-pd-fault", extra={}))
    assert got["error"] is None
    assert got["catalogs"] == ["catalog_translational"]


def test_an_unknown_type_lists_every_known_type():
    """A name the index does not know loads every catalog: the message lists all types of the slot."""
    got = _fresh(_VALIDATE.format(scenario="cw-pd-fault", extra={"controller": {"type": "nope"}}))
    assert f"(known: {', '.join(got['known'])})" in got["error"]
    assert set(got["catalogs"]) == {m.rsplit(".", 1)[1] for m in CATALOG_INDEX.values()}


def test_a_missing_type_lists_every_known_type():
    got = _fresh(_VALIDATE.format(scenario="cw-pd-fault", extra={"controller": {"k_p": 1.0}}))
    assert f"controller.type is required (one of: {', '.join(got['known'])})" in got["error"]
    assert {n for (k, n) in CATALOG_INDEX if k == "controller"} <= set(got["known"])


def test_component_type_imports_one_home():
    got = _fresh(
        "import json, sys\n"
        "from formation_ftc.methods.composed import component_type\n"
        "entry = component_type('controller', 'lqr')\n"
        "print(json.dumps([entry.module, sorted(m for m in sys.modules if '.catalog_' in m)]))\n"
    )
    assert got == ["formation_ftc.components.controllers.lqr", []]


def test_a_stale_index_entry_falls_back_to_every_catalog():
    got = _fresh(
        "import json, sys\n"
        "from formation_ftc.methods.composed import _catalog_index, component_type\n"
        "_catalog_index.CATALOG_INDEX[('controller', 'pd')] = "
        f"'{_PACKAGE}.catalog_chain'\n"
        "print(json.dumps(component_type('controller', 'pd').name))\n"
    )
    assert got == "pd"
