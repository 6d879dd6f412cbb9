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
    "catalog_attitude": (
        ("actuator", "euler-torque-allocation"),
        ("controller", "networked-el-hinf"),
        ("estimator", "scripted-fdi"),
        ("evaluation", "mehrabian-metrics"),
        ("plant", "euler-angle-attitude"),
        ("plant", "quaternion-rigid-body"),
        ("sensors", "quaternion-euler"),
    ),
    "catalog_attitude_fdi": (("estimator", "attitude-residual-fdi"),),
    "catalog_attitude_laws": (
        ("controller", "attitude-pd"),
        ("controller", "yang2013-attitude"),
        ("evaluation", "attitude-scores"),
    ),
    "catalog_attitude_truth": (("plant", "attitude-truth"),),
    "catalog_chain": (
        ("actuator", "actuator-gains"),
        ("controller", "azizi2009-llfr"),
        ("evaluation", "chain-errors"),
        ("plant", "double-integrator"),
        ("sensors", "chain-relative"),
        ("supervisor", "hierarchical"),
    ),
    "catalog_evaluations": (
        ("evaluation", "formation-scores"),
        ("evaluation", "li2020-formation-errors"),
    ),
    "catalog_faults": (
        ("actuator", "fault-battery"),
        ("network", "graph-link-loss"),
    ),
    "catalog_navigation": (
        ("estimator", "relative-navigation-filter"),
        ("estimator", "residual-fdi"),
        ("evaluation", "fdi-scores"),
    ),
    "catalog_translational": (
        ("actuator", "expression-faults"),
        ("actuator", "step-faults"),
        ("actuator", "thruster-bias"),
        ("controller", "li2020-adaptive"),
        ("controller", "none"),
        ("controller", "pd"),
        ("controller", "sir-ftc"),
        ("network", "delayed-graph"),
        ("network", "graph"),
        ("plant", "clohessy-wiltshire"),
        ("plant", "relative-lvlh"),
        ("reference", "keplerian"),
        ("sensors", "relative-state"),
    ),
    "catalog_truth": (
        ("plant", "orbital-truth"),
        ("sensors", "lvlh-relative-state"),
    ),
}

#: (kind, name) -> the module whose import registers that component type
CATALOG_INDEX: dict[tuple[str, str], str] = {
    key: f"{_PACKAGE}.{module}" for module, keys in _BY_MODULE.items() for key in keys
}
