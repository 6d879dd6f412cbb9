"""Registration of method ``azizi2009`` (in :mod:`.method`) and reproduction ``azizi2009``."""

from __future__ import annotations

from formation_ftc.papers.azizi2009.method import METHOD
from formation_ftc.papers.azizi2009.reproduction import REPRODUCTION
from formation_ftc.registry import register_reproduction

__all__ = ["METHOD"]

register_reproduction(REPRODUCTION)
