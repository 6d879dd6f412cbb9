"""Paper package gui2022: Gui et al. 2022, ILO fault reconstruction + LOF2TC.

Registers the reproduction ``gui2022``, the Theorem 1/2 conditions of its observer and laws and its
figures (see registry.PAPER_MODULES); its scenarios are composed (``scenarios/gui2022-*.toml``).
"""

from formation_ftc.papers.gui2022 import registration  # noqa: F401
