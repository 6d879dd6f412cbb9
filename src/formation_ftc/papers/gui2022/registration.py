"""Registration of Gui2022's reproduction ``gui2022``, its theorem conditions (for every composed
scenario with its observer or laws) and its figure set (``[scenario] paper = "gui2022"``)."""

from __future__ import annotations

from formation_ftc.methods.composed import register_conditions, register_paper_figures
from formation_ftc.registry import register_reproduction

_HERE = "formation_ftc.papers.gui2022"  # its modules import JAX: referenced, imported on first use
# type names as text: importing a home imports JAX, which start-up commands avoid
# (tests/papers/test_registrations.py checks each names a registered type)
register_conditions(
    "estimator", "iterative-learning-observer", f"{_HERE}.conditions:observer_conditions"
)
register_conditions("controller", "gui2022-lof2tc", f"{_HERE}.conditions:controller_conditions")
register_conditions("controller", "gui2022-cof2tc", f"{_HERE}.conditions:controller_conditions")
register_paper_figures("gui2022", f"{_HERE}.figures:plot")
register_reproduction(f"{_HERE}.reproduction:REPRODUCTION", paper="gui2022")
