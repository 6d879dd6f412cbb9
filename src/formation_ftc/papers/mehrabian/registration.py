"""Registers reproduction ``mehrabian``, the theorem conditions of the ``networked-el-hinf`` law and the
figures of scenarios with ``[scenario] paper = "mehrabian"``."""

from __future__ import annotations

from formation_ftc.methods.composed import register_conditions, register_paper_figures
from formation_ftc.methods.composed.catalog_attitude import EULER_LAW
from formation_ftc.papers.mehrabian import conditions
from formation_ftc.papers.mehrabian.figures import plot_scenario
from formation_ftc.papers.mehrabian.reproduction import REPRODUCTION
from formation_ftc.registry import register_reproduction

__all__ = ["REPRODUCTION"]

register_reproduction(REPRODUCTION)
register_conditions("controller", EULER_LAW, conditions.check)
register_paper_figures("mehrabian", plot_scenario)
