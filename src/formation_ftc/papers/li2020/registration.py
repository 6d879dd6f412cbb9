"""Registration of method ``li2020`` and reproduction ``li2020``."""

from __future__ import annotations

from formation_ftc.papers.li2020.conditions import check
from formation_ftc.papers.li2020.figures import plot_scenario
from formation_ftc.papers.li2020.method import build
from formation_ftc.papers.li2020.reproduction import REPRODUCTION
from formation_ftc.papers.li2020.schema import Li2020Scenario
from formation_ftc.registry import Method, register_method, register_reproduction

__all__ = ["METHOD"]

METHOD = register_method(Method(
    name="li2020", schema=Li2020Scenario, build=build,
    description="Li2020 nonlinear elliptic relative motion, adaptive FTC (Thm 1 / Thm 2 with delays) or SIR-FTC",
    check=check, plot=plot_scenario))
register_reproduction(REPRODUCTION)
