"""``docs/howto/add-a-component.md`` is true: its marked code blocks (``<!-- doc-test: NAME -->`` before
a fenced block) are executed. The home is written into a temporary directory on the path of
``formation_ftc.components.controllers`` (so that it is found and registered exactly as a built-in
home, by the type name alone), the page's test file is run against it, its scenario goes through the
command line (``show``, ``check``, ``run``), the unmet-need message is the real one, and the plug-in
route registers the same module from a package of its own. One short simulation compiles twice (the
page's test and ``run``)."""

from __future__ import annotations

import importlib
import re
import shlex
import sys
import tomllib
import types
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import formation_ftc.components.controllers as controllers
from formation_ftc.cli import main
from formation_ftc.components import _registry
from formation_ftc.registry import PLUGIN_GROUP

PAGE = Path(__file__).resolve().parents[2] / "docs" / "howto" / "add-a-component.md"
KIND, NAME = "controller", "drift-cancelling-pd"
HOME = "formation_ftc.components.controllers.drift_cancelling_pd"
_MARKED = re.compile(r"<!-- doc-test: ([\w-]+) -->\n```\w*\n(.*?)```", re.S)


def blocks() -> dict[str, str]:
    """The page's marked code blocks, by marker name."""
    found = _MARKED.findall(PAGE.read_text(encoding="utf-8"))
    names = [name for name, _ in found]
    assert len(set(names)) == len(names), f"a marker is used twice: {names}"
    return dict(found)


def _forget(module: str) -> None:
    """Unregister the page's type and unload ``module`` (nothing stays behind for other tests)."""
    with _registry._LOCK:
        _registry._TYPES.pop((KIND, NAME), None)
    sys.modules.pop(module, None)


@pytest.fixture
def home(tmp_path, monkeypatch):
    """The page's home module, findable as a built-in home of the controllers package."""
    folder = tmp_path / "homes"
    folder.mkdir()
    (folder / (HOME.rsplit(".", 1)[1] + ".py")).write_text(blocks()["home"], encoding="utf-8")
    _forget(HOME)
    monkeypatch.setattr(controllers, "__path__", [*controllers.__path__, str(folder)])
    yield folder
    _forget(HOME)


def test_the_page_has_every_marked_block():
    assert set(blocks()) == {"home", "test", "scenario", "commands", "unmet-need", "entry-point"}
    text = PAGE.read_text(encoding="utf-8")
    # the headings name the two files the law is
    assert "`src/formation_ftc/components/controllers/drift_cancelling_pd.py`" in text
    assert "`tests/components/controllers/test_drift_cancelling_pd.py`" in text
    assert _registry.home_module(KIND, NAME) == HOME


def test_the_home_registers_from_its_name_and_its_test_passes(home, tmp_path):
    entry = _registry.component_type(KIND, NAME)  # imports the home found from the name alone
    assert entry is not None and entry.module == HOME
    assert NAME in _registry.type_names(KIND)
    section = entry.section.model_validate({"kp": 1.0, "kd": 1.0})
    assert section.nominal_mass == 100.0  # the flight default the page states (NOMINAL_MASS)
    # the page's test file, run as pytest would: every test_ function
    module = types.ModuleType("test_drift_cancelling_pd")
    exec(compile(blocks()["test"], "test_drift_cancelling_pd.py", "exec"), module.__dict__)
    tests = [f for name, f in vars(module).items() if name.startswith("test_")]
    assert len(tests) == 2
    for test in tests:
        test()


def test_the_scenario_runs_from_the_command_line(home, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    scenario = blocks()["scenario"]
    Path("drift-cancelling-pd-demo.toml").write_text(scenario, encoding="utf-8")
    commands = [shlex.split(line) for line in blocks()["commands"].splitlines() if line.strip()]
    assert [c[:2] for c in commands] == [["formation-ftc", s] for s in ("show", "check", "run")]
    for argv in commands:
        assert main(argv[1:]) == 0, argv
    out = capsys.readouterr().out
    assert 'type = "drift-cancelling-pd"' in out  # show
    assert re.search(r"RK4 step damps eq\. \(2\) .* yes", out)  # check: the law's condition holds
    # run: the recorded positions against the closed form of eq. (2) (critical damping, at rest)
    raw = tomllib.loads(scenario)
    w = float(np.sqrt(raw["controller"]["kp"]))
    assert raw["controller"]["kd"] == pytest.approx(2 * w)
    with xr.open_dataset(Path(commands[2][commands[2].index("--out") + 1]) / "result.nc") as ds:
        t = ds.time.values[:, None, None]
        e0 = np.array(raw["plant"]["initial_position"])
        expected = (e0 + w * e0 * t) * np.exp(-w * t)
        np.testing.assert_allclose(ds.position.values, expected, rtol=0, atol=1e-5)


def test_an_unmet_need_gives_the_message_of_the_page(home, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    without = re.sub(r"\[reference\].*?\n\n", "", blocks()["scenario"], flags=re.S)
    assert "[reference]" not in without and "[controller]" in without
    Path("no-reference.toml").write_text(without, encoding="utf-8")
    assert main(["check", "no-reference.toml"]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert " ".join(blocks()["unmet-need"].split()) in err


def test_the_plug_in_route_registers_the_same_module(tmp_path, monkeypatch):
    table = tomllib.loads(blocks()["entry-point"])["project"]["entry-points"]
    assert list(table) == [PLUGIN_GROUP]
    (module,) = table[PLUGIN_GROUP].values()
    package, stem = module.rsplit(".", 1)
    folder = tmp_path / package
    folder.mkdir()
    (folder / "__init__.py").write_text("", encoding="utf-8")
    (folder / f"{stem}.py").write_text(blocks()["home"], encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    _forget(module)
    try:
        importlib.import_module(module)  # what the entry point does: outside the package, any name
        entry = _registry.component_type(KIND, NAME)
        assert entry is not None and entry.module == module
    finally:
        _forget(module)
        sys.modules.pop(package, None)
