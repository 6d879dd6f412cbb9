"""Registration of the paper's parts of composed scenarios: its design conditions for the law
(``controller.type = "azizi2009-llfr"``), its run figure (``[scenario] paper = "azizi2009"``) and the
reproduction ``azizi2009``."""

from __future__ import annotations

from formation_ftc.methods.composed import register_conditions, register_paper_figures
from formation_ftc.methods.composed.catalog_chain import CHAIN_LAW
from formation_ftc.papers.azizi2009.conditions import conditions
from formation_ftc.papers.azizi2009.figures import plot_run
from formation_ftc.papers.azizi2009.reproduction import REPRODUCTION
from formation_ftc.registry import register_reproduction

register_conditions("controller", CHAIN_LAW, conditions)
register_paper_figures("azizi2009", plot_run)
register_reproduction(REPRODUCTION)
