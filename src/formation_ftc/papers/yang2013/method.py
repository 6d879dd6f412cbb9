"""Registration of method ``yang2013`` (schema, build, check, plot)."""

from __future__ import annotations

from formation_ftc.papers.yang2013.checks import check
from formation_ftc.papers.yang2013.figures import plot_scenario
from formation_ftc.papers.yang2013.model import build
from formation_ftc.papers.yang2013.schema import Yang2013Scenario
from formation_ftc.registry import Method, register_method

__all__ = ["METHOD"]

METHOD = register_method(Method(
    name="yang2013",
    schema=Yang2013Scenario,
    build=build,
    description="Yang2013 state-varying switched formation (docking, undocking, departure, participation), "
                "error-level closed loop of (12)-(13), dwell-time supervisor and fault tolerance by switching",
    check=check,
    plot=plot_scenario,
))
