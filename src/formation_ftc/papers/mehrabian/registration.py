"""Registers reproduction ``mehrabian``, the theorem conditions of the ``networked-el-hinf`` law, the
command-model condition of the ``attitude-residual-fdi`` that reports to it and the figures of
scenarios with ``[scenario] paper = "mehrabian"``."""

from __future__ import annotations

from formation_ftc.methods.composed import register_conditions, register_paper_figures
from formation_ftc.registry import register_reproduction

# its modules import JAX: referenced, imported on first use
_HERE = "formation_ftc.papers.mehrabian"
register_reproduction(f"{_HERE}.reproduction:REPRODUCTION", paper="mehrabian")
# type names as text: importing a home imports JAX, which start-up commands avoid
# (tests/papers/test_registrations.py checks each names a registered type)
register_conditions("controller", "networked-el-hinf", f"{_HERE}.conditions:check")
register_conditions("estimator", "attitude-residual-fdi", f"{_HERE}.conditions:fdi_check")
register_paper_figures("mehrabian", f"{_HERE}.figures:plot_scenario")
