"""The papers' registrations name component types as text (no home imported at start-up): every name
must be a registered type, and every paper's conditions reference its own modules."""

from __future__ import annotations

from formation_ftc.components._registry import component_type, home_module
from formation_ftc.methods.composed import _CONDITIONS
from formation_ftc.registry import load_plugins


def test_every_registered_condition_names_a_type_with_a_home():
    load_plugins()
    named = {key for key, refs in _CONDITIONS.items() if any(isinstance(r, str) for r in refs)}
    assert {("estimator", "iterative-learning-observer"), ("supervisor", "switching")} <= named
    for kind, name in named:
        entry = component_type(kind, name)
        assert entry is not None, f"{kind} {name!r} is registered with conditions but is no type"
        assert entry.module == home_module(kind, name)
        refs = [r for r in _CONDITIONS[(kind, name)] if isinstance(r, str)]
        assert all(r.startswith("formation_ftc.papers.") for r in refs), refs
