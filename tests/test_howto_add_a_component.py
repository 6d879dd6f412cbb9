"""docs/howto/add-a-component.md stays true: its home module is dropped into the controllers' package
(as a new file of ``components/controllers/`` would be), its test file runs and passes, and the
composition message it shows is the one ``ClosedLoop.validate`` gives."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

import formation_ftc.components.controllers as controllers
from formation_ftc.components import _registry

DOC = Path(__file__).resolve().parents[1] / "docs" / "howto" / "add-a-component.md"


def _blocks() -> dict[str, str]:
    text = DOC.read_text()
    found = re.findall(r"<!-- (file: \S+|message) -->\n```\w+\n(.*?)```", text, flags=re.S)
    return {label: body for label, body in found}


@pytest.fixture
def home(tmp_path, monkeypatch):
    """The walkthrough's home as ``formation_ftc.components.controllers.damped_spring``."""
    blocks = _blocks()
    (tmp_path / "damped_spring.py").write_text(
        blocks["file: components/controllers/damped_spring.py"]
    )
    monkeypatch.setattr(controllers, "__path__", [*controllers.__path__, str(tmp_path)])
    yield blocks
    _registry._TYPES.pop(("controller", "damped-spring"), None)
    sys.modules.pop("formation_ftc.components.controllers.damped_spring", None)


def test_the_walkthrough_home_registers_and_its_test_passes(home, tmp_path):
    assert _registry.component_type("controller", "damped-spring").module == (
        "formation_ftc.components.controllers.damped_spring"
    )
    namespace: dict = {"__name__": "walkthrough_test"}
    exec(
        compile(home["file: tests/components/controllers/test_damped_spring.py"], "test", "exec"),
        namespace,
    )
    tests = [f for name, f in namespace.items() if name.startswith("test_")]
    assert len(tests) == 2
    for test in tests:
        test()


def test_the_message_shown_is_the_one_validate_gives(home):
    from formation_ftc.api import load_scenario
    from formation_ftc.config.loader import ScenarioError

    namespace: dict = {"__name__": "walkthrough_test"}
    exec(
        compile(home["file: tests/components/controllers/test_damped_spring.py"], "test", "exec"),
        namespace,
    )
    raw = {**namespace["SCENARIO"], "sensors": {"type": "chain-relative"}}
    with pytest.raises(ScenarioError) as err:
        load_scenario(raw)
    assert home["message"].strip() in str(err.value)
