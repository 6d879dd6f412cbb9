"""Registration of Gui2022's reproduction ``gui2022``, its theorem conditions (for every composed
scenario with its observer or laws) and its figure set (``[scenario] paper = "gui2022"``)."""

from __future__ import annotations

from formation_ftc.methods.composed import register_conditions, register_paper_figures
from formation_ftc.methods.composed.catalog_learning import COF2TC, ILO, LOF2TC
from formation_ftc.papers.gui2022.conditions import controller_conditions, observer_conditions
from formation_ftc.papers.gui2022.figures import plot
from formation_ftc.papers.gui2022.reproduction import REPRODUCTION
from formation_ftc.registry import register_reproduction

register_conditions("estimator", ILO, observer_conditions)
register_conditions("controller", LOF2TC, controller_conditions)
register_conditions("controller", COF2TC, controller_conditions)
register_paper_figures("gui2022", plot)
register_reproduction(REPRODUCTION)
