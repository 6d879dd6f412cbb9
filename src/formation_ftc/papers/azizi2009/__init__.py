"""Azizi & Khorasani (ACC 2009): hierarchical cooperative fault accommodation of formation flying
satellites in deep space. Registers method ``azizi2009`` and reproduction ``azizi2009`` (SPEC.md P4,
ERRATA E004-*).
"""

from formation_ftc.papers.azizi2009 import method, reproduction  # noqa: F401
