"""Registers reproduction ``mehrabian``, the theorem conditions of the ``networked-el-hinf`` law and the
figures of scenarios with ``[scenario] paper = "mehrabian"``."""

from __future__ import annotations

from formation_ftc.methods.composed import register_conditions, register_paper_figures
from formation_ftc.registry import register_reproduction

_HERE = (
    "formation_ftc.papers.mehrabian"  # its modules import JAX: referenced, imported on first use
)
register_reproduction(f"{_HERE}.reproduction:REPRODUCTION", paper="mehrabian")
# type names as text, not the catalog's constants: importing a catalog module costs start-up time
# (tests/methods/composed/test_catalog_index.py checks they match)
register_conditions("controller", "networked-el-hinf", f"{_HERE}.conditions:check")
register_paper_figures("mehrabian", f"{_HERE}.figures:plot_scenario")
