"""Registers reproduction ``li2020``, the conditions of its laws for composed scenarios (controller
``li2020-adaptive`` or ``sir-ftc``) and its figures (``[scenario] paper = "li2020"``)."""

from __future__ import annotations

from formation_ftc.methods.composed import register_conditions, register_paper_figures
from formation_ftc.registry import register_reproduction

_HERE = "formation_ftc.papers.li2020"  # its modules import JAX: referenced, imported on first use
register_reproduction(f"{_HERE}.reproduction:REPRODUCTION", paper="li2020")
register_conditions("controller", "li2020-adaptive", f"{_HERE}.conditions:check")
register_conditions("controller", "sir-ftc", f"{_HERE}.conditions:check")
register_paper_figures("li2020", f"{_HERE}.figures:plot_scenario")
