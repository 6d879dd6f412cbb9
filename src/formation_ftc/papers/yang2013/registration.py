"""Registration of reproduction ``yang2013``, its theorem conditions (for the ``switching``
supervisor) and its figures (scenarios with ``[scenario] paper = "yang2013"``)."""

from __future__ import annotations

from formation_ftc.methods.composed import register_conditions, register_paper_figures
from formation_ftc.registry import register_reproduction

_HERE = "formation_ftc.papers.yang2013"  # its modules import JAX: referenced, imported on first use
register_reproduction(f"{_HERE}.reproduction:REPRODUCTION", paper="yang2013")
# type names as text: importing a home imports JAX, which start-up commands avoid
# (tests/papers/test_registrations.py checks each names a registered type)
register_conditions("supervisor", "switching", f"{_HERE}.conditions:conditions")
register_paper_figures("yang2013", f"{_HERE}.figures:plot_scenario")
