"""``formation_ftc.components`` exports the component classes of every home (issue 46 item 5)."""

from __future__ import annotations

import importlib

import pytest

import formation_ftc.components as components
from formation_ftc.components import _registry
from formation_ftc.sim.components import _Kind


def test_every_home_class_is_exported_once_under_its_own_name():
    seen: dict[str, type] = {}
    for kind in _registry.KINDS:
        for module in _registry._homes(kind):
            mod = importlib.import_module(module)
            for name in getattr(mod, "__all__", ()):
                obj = getattr(mod, name)
                if isinstance(obj, type) and issubclass(obj, _Kind):
                    assert seen.setdefault(name, obj) is obj, f"two classes named {name}"
                    assert getattr(components, name) is obj
    assert "LqrFormationController" in seen and "LqrFormationController" in dir(components)
    assert len(seen) > 40  # every kind's homes contribute


def test_an_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="has no attribute 'NoSuchPlant'"):
        components.NoSuchPlant  # noqa: B018
