"""Azizi & Khorasani (ACC 2009): hierarchical cooperative fault accommodation of formation flying
satellites in deep space. Registers method ``azizi2009`` and reproduction ``azizi2009`` (errata E004-*
in docs/errata.md).
"""

from formation_ftc.papers.azizi2009 import registration  # noqa: F401
