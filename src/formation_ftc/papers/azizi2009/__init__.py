"""Azizi & Khorasani (ACC 2009): hierarchical cooperative fault accommodation of formation flying
satellites in deep space. Its scenarios are composed (``azizi2009-*``); this package registers the
law's design conditions, the run figure and reproduction ``azizi2009`` (errata E004-* in
docs/errata.md).
"""

from formation_ftc.papers.azizi2009 import registration  # noqa: F401
