"""Mehrabian, Tafazoli, Khorasani: reconfigurable control of networked nonlinear Euler-Lagrange systems
subject to FDI imperfections. Registers method ``mehrabian`` and reproduction ``mehrabian``
(SPEC.md P3, ERRATA E003-*).
"""

from formation_ftc.papers.mehrabian import registration  # noqa: F401
