"""Registers reproduction ``mehrabian``, the theorem conditions of the ``networked-el-hinf`` law and the
figures of scenarios with ``[scenario] paper = "mehrabian"``."""

from __future__ import annotations

from formation_ftc.methods.composed import register_conditions, register_paper_figures
from formation_ftc.methods.composed.catalog_attitude import EULER_LAW
from formation_ftc.registry import register_reproduction

_HERE = (
    "formation_ftc.papers.mehrabian"  # its modules import JAX: referenced, imported on first use
)
register_reproduction(f"{_HERE}.reproduction:REPRODUCTION", paper="mehrabian")
register_conditions("controller", EULER_LAW, f"{_HERE}.conditions:check")
register_paper_figures("mehrabian", f"{_HERE}.figures:plot_scenario")
