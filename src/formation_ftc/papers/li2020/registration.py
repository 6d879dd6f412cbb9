"""Registers reproduction ``li2020`` (method ``li2020`` is registered by :mod:`.method`)."""

from __future__ import annotations

from formation_ftc.papers.li2020 import method  # noqa: F401  (registers the method)
from formation_ftc.papers.li2020.reproduction import REPRODUCTION
from formation_ftc.registry import register_reproduction

__all__ = ["REPRODUCTION"]

register_reproduction(REPRODUCTION)
