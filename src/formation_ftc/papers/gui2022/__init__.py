"""Paper package gui2022: Gui et al. 2022, ILO fault reconstruction + LOF2TC.

Registers the method ``gui2022`` and the reproduction ``gui2022`` (see registry.PAPER_MODULES).
"""

from formation_ftc.papers.gui2022 import registration  # noqa: F401
