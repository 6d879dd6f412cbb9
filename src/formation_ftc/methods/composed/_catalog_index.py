"""Which catalog module registers each built-in component type: ``(kind, name)`` -> module.

Validating a composed scenario (``formation-ftc show``) imports only the catalog modules of the types
it names instead of every ``catalog_*.py`` (issue 37 item 2: start-up time of the text commands). A
name missing here loads every catalog, so a stale entry costs time, not correctness; a test checks
this table against what loading all catalogs registers (``tests/methods/composed``).
"""

from __future__ import annotations

__all__ = ["CATALOG_INDEX"]

_PACKAGE = "formation_ftc.methods.composed"

#: catalog module (in this package) -> the (kind, name) component types its import registers
_BY_MODULE: dict[str, tuple[tuple[str, str], ...]] = {
    "catalog_delays": (
        ("controller", "yang2013-relative"),
        ("controller", "yang2013-translational"),
    ),
    "catalog_learning": (
        ("controller", "gui2022-cof2tc"),
        ("controller", "gui2022-lof2tc"),
        ("estimator", "iterative-learning-observer"),
        ("evaluation", "gui2022-scores"),
        ("plant", "clohessy-wiltshire-zoh"),
    ),
    "catalog_switched": (
        ("actuator", "velocity-gain-fault"),
        ("controller", "yang2013-force-torque"),
        ("estimator", "scheduled-diagnosis"),
        ("evaluation", "switch-norms"),
        ("plant", "switched-formation"),
        ("sensors", "tracking-error"),
        ("supervisor", "switching"),
    ),
}

#: (kind, name) -> the module whose import registers that component type
CATALOG_INDEX: dict[tuple[str, str], str] = {
    key: f"{_PACKAGE}.{module}" for module, keys in _BY_MODULE.items() for key in keys
}
