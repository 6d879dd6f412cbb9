"""Registers reproduction ``mehrabian`` (method ``mehrabian`` is registered by :mod:`.method`)."""

from __future__ import annotations

from formation_ftc.papers.mehrabian import method  # noqa: F401  (registers the method)
from formation_ftc.papers.mehrabian.reproduction import REPRODUCTION
from formation_ftc.registry import register_reproduction

__all__ = ["REPRODUCTION"]

register_reproduction(REPRODUCTION)
