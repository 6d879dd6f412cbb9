"""Registers reproduction ``li2020``, the conditions of its laws for composed scenarios (controller
``li2020-adaptive`` or ``sir-ftc``) and its figures (``[scenario] paper = "li2020"``)."""

from __future__ import annotations

from formation_ftc.methods.composed import register_conditions, register_paper_figures
from formation_ftc.papers.li2020.conditions import check
from formation_ftc.papers.li2020.figures import plot_scenario
from formation_ftc.papers.li2020.reproduction import REPRODUCTION
from formation_ftc.registry import register_reproduction

__all__ = ["REPRODUCTION"]

register_reproduction(REPRODUCTION)
register_conditions("controller", "li2020-adaptive", check)
register_conditions("controller", "sir-ftc", check)
register_paper_figures("li2020", plot_scenario)
