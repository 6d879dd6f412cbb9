"""Registration of method ``li2020`` (in :mod:`.method`) and reproduction ``li2020``."""

from __future__ import annotations

from formation_ftc.papers.li2020.method import METHOD
from formation_ftc.papers.li2020.reproduction import REPRODUCTION
from formation_ftc.registry import register_reproduction

__all__ = ["METHOD"]

register_reproduction(REPRODUCTION)
