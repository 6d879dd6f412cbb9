"""Registration of Gui2022's reproduction ``gui2022``, its theorem conditions (for every composed
scenario with its observer or laws) and its figure set (``[scenario] paper = "gui2022"``)."""

from __future__ import annotations

from formation_ftc.methods.composed import register_conditions, register_paper_figures
from formation_ftc.methods.composed.catalog_learning import COF2TC, ILO, LOF2TC
from formation_ftc.registry import register_reproduction

_HERE = "formation_ftc.papers.gui2022"  # its modules import JAX: referenced, imported on first use
register_conditions("estimator", ILO, f"{_HERE}.conditions:observer_conditions")
register_conditions("controller", LOF2TC, f"{_HERE}.conditions:controller_conditions")
register_conditions("controller", COF2TC, f"{_HERE}.conditions:controller_conditions")
register_paper_figures("gui2022", f"{_HERE}.figures:plot")
register_reproduction(f"{_HERE}.reproduction:REPRODUCTION", paper="gui2022")
