"""Registration of method ``yang2013`` (in :mod:`.method`) and reproduction ``yang2013``."""

from __future__ import annotations

from formation_ftc.papers.yang2013.method import METHOD
from formation_ftc.papers.yang2013.reproduction import REPRODUCTION
from formation_ftc.registry import register_reproduction

__all__ = ["METHOD"]

register_reproduction(REPRODUCTION)
