"""Registration of reproduction ``yang2013``, its theorem conditions (for the ``switching``
supervisor) and its figures (scenarios with ``[scenario] paper = "yang2013"``)."""

from __future__ import annotations

from formation_ftc.methods.composed import register_conditions, register_paper_figures
from formation_ftc.methods.composed.catalog_switched import SWITCHING_SUPERVISOR
from formation_ftc.papers.yang2013.conditions import conditions
from formation_ftc.papers.yang2013.figures import plot_scenario
from formation_ftc.papers.yang2013.reproduction import REPRODUCTION
from formation_ftc.registry import register_reproduction

register_reproduction(REPRODUCTION)
register_conditions("supervisor", SWITCHING_SUPERVISOR, conditions)
register_paper_figures("yang2013", plot_scenario)
