"""Registration of the paper's parts of composed scenarios: its design conditions for the law
(``controller.type = "azizi2009-llfr"``), its run figure (``[scenario] paper = "azizi2009"``) and the
reproduction ``azizi2009``."""

from __future__ import annotations

from formation_ftc.methods.composed import register_conditions, register_paper_figures
from formation_ftc.registry import register_reproduction

# its modules import JAX: referenced, imported on first use
_HERE = "formation_ftc.papers.azizi2009"
# type names as text: importing a home imports JAX, which start-up commands avoid
# (tests/papers/test_registrations.py checks each names a registered type)
register_conditions("controller", "azizi2009-llfr", f"{_HERE}.conditions:conditions")
register_paper_figures("azizi2009", f"{_HERE}.figures:plot_run")
register_reproduction(f"{_HERE}.reproduction:REPRODUCTION", paper="azizi2009")
