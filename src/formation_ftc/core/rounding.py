"""Rounding margins of floating-point eigenvalue computations (for conditions with basis "exact").

LAPACK's nonsymmetric eigenvalue solver is backward stable: the computed eigenvalues are exact
eigenvalues of ``M + E`` with ``||E||_2 <= c n eps ||M||_2``. By the Bauer-Fike theorem every eigenvalue
of ``M + E`` lies within ``kappa_2(V) ||E||_2`` of an eigenvalue of ``M`` (V: eigenvectors, M
diagonalisable). :func:`eigenvalue_margin` returns that distance with ``c = 10`` and the condition number
of the computed eigenvectors; a claim such as ``max Re(lambda) < 0`` is only decided when the computed
value clears the margin. A defective (or nearly defective) matrix gives a huge or infinite margin:
nothing is decided from its eigenvalues.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["eigenvalue_margin"]


def eigenvalue_margin(M) -> float:
    """Bound on |computed - exact| of the eigenvalues of the square matrix M (Bauer-Fike) [units of M]."""
    M = np.atleast_2d(np.asarray(M, dtype=float))
    n = M.shape[0]
    if n == 0:
        return 0.0
    _, V = np.linalg.eig(M)
    with np.errstate(all="ignore"):
        kappa = float(np.linalg.cond(V))
    if not math.isfinite(kappa):
        return math.inf
    return float(kappa * 10 * n * np.finfo(float).eps * np.linalg.norm(M, 2))
