"""Registration of the ``gui2022`` method and reproduction."""

from __future__ import annotations

from formation_ftc.papers.gui2022 import reproduction  # noqa: F401  (registers the reproduction)
from formation_ftc.papers.gui2022.conditions import check
from formation_ftc.papers.gui2022.figures import plot
from formation_ftc.papers.gui2022.method import build
from formation_ftc.papers.gui2022.schema import Gui2022Scenario
from formation_ftc.registry import Method, register_method

__all__ = ["METHOD"]

METHOD = register_method(Method(
    name="gui2022", schema=Gui2022Scenario, build=build,
    description="Gui2022: CW deputy, iterative learning observer (5), LOF2TC (30)-(32) / COF2TC baseline",
    check=check, plot=plot,
))
