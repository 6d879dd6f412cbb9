"""Concrete components of the closed loop (the contract is :mod:`formation_ftc.sim.components`).

Every component type has one home, ``components/<kind>/<name>.py``: its equations (pure functions of
arrays, with the paper's equation numbers), its ``@component`` class, its TOML section, its builder and
its registration; shared dynamics live in :mod:`formation_ftc.core`. A component declares what it
provides and needs (:mod:`formation_ftc.sim.contract`), so a law written for one paper runs on any plant
that provides what it needs. Layer: below ``config``/``campaign``/``papers``, above ``sim``.
"""

from __future__ import annotations

from typing import Any

__all__: list[str] = []  # the component classes are found on first use (see __getattr__)


def _component_classes() -> dict[str, type]:
    """Every component class of the built-in homes by name (each home imported; JAX with them)."""
    import importlib

    from formation_ftc.components import _registry
    from formation_ftc.sim.components import _Kind

    found: dict[str, type] = {}
    for kind in _registry.KINDS:
        for module in _registry._homes(kind):
            mod = importlib.import_module(module)
            for name in getattr(mod, "__all__", ()):
                obj = getattr(mod, name)
                if isinstance(obj, type) and issubclass(obj, _Kind):
                    found.setdefault(name, obj)
    return found


def __getattr__(name: str) -> Any:
    """A component class by name, e.g. ``formation_ftc.components.LqrFormationController``: the
    package exports every component type's class from its home (``components/<kind>/<name>.py``),
    imported on first use so that ``import formation_ftc.components`` stays cheap."""
    if name[:1].isupper():  # class names only: `from . import plants` must not import every home
        classes = _component_classes()
        if name in classes:
            return classes[name]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_component_classes()})
