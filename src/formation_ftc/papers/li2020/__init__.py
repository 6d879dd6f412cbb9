"""Li, Liu, He, Liu, Liu (IEEE Access 2020): distributed adaptive FTC for spacecraft formation with
communication delays. Registers method ``li2020`` and reproduction ``li2020`` (errata E000-* in docs/errata.md).
"""

from formation_ftc.papers.li2020 import registration  # noqa: F401
