"""Mehrabian, Tafazoli, Khorasani: reconfigurable control of networked nonlinear Euler-Lagrange systems
subject to FDI imperfections. Registers reproduction ``mehrabian``, the law's conditions and the paper's
figures; its scenarios are composed (errata E003-* in docs/errata.md).
"""

from formation_ftc.papers.mehrabian import registration  # noqa: F401
