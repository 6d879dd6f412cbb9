"""Registration of method ``gui2022`` (in :mod:`.method`) and reproduction ``gui2022``."""

from __future__ import annotations

from formation_ftc.papers.gui2022.method import METHOD
from formation_ftc.papers.gui2022.reproduction import REPRODUCTION
from formation_ftc.registry import register_reproduction

__all__ = ["METHOD"]

register_reproduction(REPRODUCTION)
