"""Continuous algebraic Riccati equation (CARE) with a residual certificate.

Solves ``P A + A^T P - P B R^-1 B^T P + Q = 0`` with :func:`scipy.linalg.solve_continuous_are` and
reports ``max |P A + A^T P - P B R^-1 B^T P + Q|`` so a caller can certify the solution. Used by the
Gui2022 LOF2TC design, eqs. (34)-(35) (Q = 4e-5 I6, R = I3 reproduces the printed P1, E002-05).
Offline design code (numpy/scipy); never called inside the time loop.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

__all__ = ["CareSolution", "solve_care", "care_residual"]


@dataclass(frozen=True)
class CareSolution:
    """Stabilising CARE solution.

    Attributes
    ----------
    P : (n, n) symmetric positive (semi)definite solution.
    K : (m, n) optimal gain ``R^-1 B^T P``.
    residual : ``max |P A + A^T P - P B R^-1 B^T P + Q|`` (absolute, same units as Q).
    closed_loop_eigenvalues : eigenvalues of ``A - B K`` [1/s].
    """

    P: np.ndarray
    K: np.ndarray
    residual: float
    closed_loop_eigenvalues: np.ndarray


def care_residual(P, A, B, Q, R) -> float:
    """``max |P A + A^T P - P B R^-1 B^T P + Q|`` (element-wise max norm).

    Parameters
    ----------
    P : array_like, shape (n, n)
        Candidate solution.
    A : array_like, shape (n, n)
        System matrix [1/s].
    B : array_like, shape (n, m)
        Input matrix.
    Q : array_like, shape (n, n)
        State weight.
    R : array_like, shape (m, m)
        Input weight (invertible).

    Returns
    -------
    float
        The absolute residual, in the units of Q.

    Examples
    --------
    >>> from formation_ftc.design.riccati import care_residual
    >>> care_residual([[1.0]], [[0.0]], [[1.0]], [[1.0]], [[1.0]])  # x' = u, Q = R = 1: P = 1
    0.0
    >>> care_residual([[2.0]], [[0.0]], [[1.0]], [[1.0]], [[1.0]])  # |-4 + 1|
    3.0
    """
    P, A, B, Q, R = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (P, A, B, Q, R))
    res = P @ A + A.T @ P - P @ B @ np.linalg.solve(R, B.T @ P) + Q
    return float(np.max(np.abs(res)))


def solve_care(A, B, Q, R) -> CareSolution:
    """Solve the CARE ``P A + A^T P - P B R^-1 B^T P + Q = 0`` (Gui2022 eq. (34) with R = I).

    Raises ``ValueError`` with the reason when no stabilising solution exists (e.g. (A, B) not
    stabilisable or Q/R not positive (semi)definite).

    Parameters
    ----------
    A : array_like, shape (n, n)
        System matrix [1/s].
    B : array_like, shape (n, m)
        Input matrix.
    Q : array_like, shape (n, n)
        State weight (symmetric, >= 0).
    R : array_like, shape (m, m)
        Input weight (symmetric, > 0).

    Returns
    -------
    CareSolution
        P, the gain K = R^-1 B^T P, the residual of :func:`care_residual` and the closed-loop eigenvalues
        [1/s].

    Raises
    ------
    ValueError
        Inconsistent shapes, R not positive definite, Q not positive semidefinite, or no stabilising
        solution.

    Examples
    --------
    Double integrator with Q = I, R = 1: P = [[sqrt(3), 1], [1, sqrt(3)]]:

    >>> import numpy as np
    >>> from formation_ftc.design.riccati import solve_care
    >>> s = solve_care([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0]], np.eye(2), [[1.0]])
    >>> np.round(s.P, 6)
    array([[1.732051, 1.      ],
           [1.      , 1.732051]])
    >>> s.residual < 1e-12
    True
    """
    A, B, Q, R = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (A, B, Q, R))
    n, m = A.shape[0], B.shape[1]
    if A.shape != (n, n) or B.shape[0] != n or Q.shape != (n, n) or R.shape != (m, m):
        raise ValueError(
            f"CARE: inconsistent shapes A{A.shape}, B{B.shape}, Q{Q.shape}, R{R.shape}"
        )
    if np.min(np.linalg.eigvalsh((R + R.T) / 2)) <= 0:
        raise ValueError("CARE: R must be symmetric positive definite")
    if np.min(np.linalg.eigvalsh((Q + Q.T) / 2)) < -1e-14 * max(1.0, np.abs(Q).max()):
        raise ValueError("CARE: Q must be symmetric positive semidefinite")
    try:
        P = scipy.linalg.solve_continuous_are(A, B, Q, R)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise ValueError(f"CARE has no stabilising solution: {exc}") from None
    P = (P + P.T) / 2
    K = np.linalg.solve(R, B.T @ P)
    return CareSolution(P, K, care_residual(P, A, B, Q, R), np.linalg.eigvals(A - B @ K))
