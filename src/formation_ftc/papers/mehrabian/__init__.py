"""Mehrabian, Tafazoli, Khorasani: reconfigurable control of networked nonlinear Euler-Lagrange systems
subject to FDI imperfections. Registers method ``mehrabian`` and reproduction ``mehrabian``
(errata E003-* in docs/errata.md).
"""

from formation_ftc.papers.mehrabian import registration  # noqa: F401
