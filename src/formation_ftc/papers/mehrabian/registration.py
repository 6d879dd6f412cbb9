"""Registers method ``mehrabian`` and reproduction ``mehrabian``."""

from __future__ import annotations

from formation_ftc.papers.mehrabian import conditions
from formation_ftc.papers.mehrabian.method import build
from formation_ftc.papers.mehrabian.schema import MehrabianScenario
from formation_ftc.registry import Method, register_method

__all__ = ["METHOD"]


def _plot(ds, scenario, out_dir):
    from formation_ftc.papers.mehrabian.figures import plot_scenario

    return plot_scenario(ds, scenario, out_dir)


METHOD = register_method(Method(
    name="mehrabian",
    schema=MehrabianScenario,
    build=build,
    description="Networked EL spacecraft attitudes: distributed H-infinity sync law (8) with adaptive "
                "fault recovery (18)-(19) under FDI imperfections (Mehrabian et al.)",
    check=conditions.check,
    plot=_plot,
))


from formation_ftc.papers.mehrabian.reproduction import REPRODUCTION  # noqa: E402
from formation_ftc.registry import register_reproduction  # noqa: E402

register_reproduction(REPRODUCTION)
