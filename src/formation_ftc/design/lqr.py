"""Linear-quadratic regulator (LQR) designed on the Clohessy-Wiltshire model, weights by Bryson's rule.

The gain minimises ``J = int (e^T Q e + a^T R a) dt`` for ``e_dot = A e + B a`` (a: commanded
acceleration [m/s^2]) and is ``K = R^-1 B^T P`` with P the stabilising solution of the continuous
algebraic Riccati equation (CARE) ``A^T P + P A - P B R^-1 B^T P + Q = 0``, solved by
:func:`formation_ftc.design.riccati.solve_care` (scipy's ``solve_continuous_are``).

Bryson's rule: each state and input is weighted by the inverse square of its largest acceptable value,
``Q = diag(1 / e_max^2)``, ``R = diag(1 / a_max^2)``, so the designer states a maximum position error
[m], velocity error [m/s] and acceleration [m/s^2] instead of abstract weights.

Offline design code (numpy/scipy); never called inside the time loop.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from formation_ftc.core.dynamics.cw import cw_matrices
from formation_ftc.design.riccati import solve_care

__all__ = ["LqrDesign", "bryson_weights", "lqr", "cw_lqr", "care_relative_residual"]


@dataclass(frozen=True)
class LqrDesign:
    """An LQR design.

    Attributes
    ----------
    K : (m, n) gain ``R^-1 B^T P``; for the CW model (3, 6) [1/s^2 | 1/s] (acceleration per error).
    P : (n, n) stabilising CARE solution (symmetric positive definite).
    Q, R : the weights the gain was designed with.
    A, B : the model the gain was designed on.
    relative_residual : :func:`care_relative_residual` of P [-].
    closed_loop_eigenvalues : eigenvalues of ``A - B K`` [1/s].
    """

    K: np.ndarray
    P: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    A: np.ndarray
    B: np.ndarray
    relative_residual: float
    closed_loop_eigenvalues: np.ndarray


def _positive(value, size: int, name: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        arr = np.full(size, float(arr))
    if arr.shape != (size,):
        raise ValueError(f"{name}: {arr.size} values, expected one number or {size}")
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise ValueError(f"{name}: every value must be finite and > 0")
    return arr


def bryson_weights(max_state, max_input) -> tuple[np.ndarray, np.ndarray]:
    """Bryson's rule: ``Q = diag(1 / max_state^2)``, ``R = diag(1 / max_input^2)``.

    Parameters
    ----------
    max_state : array_like, shape (n,)
        Largest acceptable value of each state (same units as the state, e.g. [m] or [m/s]); > 0.
    max_input : array_like, shape (m,)
        Largest acceptable value of each input (same units as the input, e.g. [m/s^2]); > 0.

    Returns
    -------
    Q : numpy.ndarray, shape (n, n)
        State weight [1 / state unit^2].
    R : numpy.ndarray, shape (m, m)
        Input weight [1 / input unit^2].

    Raises
    ------
    ValueError
        A value that is not finite and > 0.

    Examples
    --------
    >>> from formation_ftc.design.lqr import bryson_weights
    >>> Q, R = bryson_weights([10.0, 0.5], [0.1])
    >>> Q
    array([[0.01, 0.  ],
           [0.  , 4.  ]])
    >>> R.round(6)
    array([[100.]])
    """
    xs = _positive(max_state, np.size(max_state), "max_state")
    us = _positive(max_input, np.size(max_input), "max_input")
    return np.diag(1.0 / xs**2), np.diag(1.0 / us**2)


def care_relative_residual(P, A, B, Q, R) -> float:
    """``||A^T P + P A - P B R^-1 B^T P + Q||_F`` divided by the sum of the Frobenius norms of the four
    terms [-]: 0 for an exact solution, about machine precision for a well-solved one.

    Parameters
    ----------
    P : array_like, shape (n, n)
        Candidate CARE solution.
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
        The relative residual [-].

    Examples
    --------
    Scalar ``x' = u`` with Q = R = 1 has P = 1:

    >>> from formation_ftc.design.lqr import care_relative_residual
    >>> care_relative_residual([[1.0]], [[0.0]], [[1.0]], [[1.0]], [[1.0]])
    0.0
    >>> care_relative_residual([[2.0]], [[0.0]], [[1.0]], [[1.0]], [[1.0]])  # |-4 + 1| / (4 + 1)
    0.6
    """
    P, A, B, Q, R = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (P, A, B, Q, R))
    terms = (A.T @ P, P @ A, -P @ B @ np.linalg.solve(R, B.T @ P), Q)
    scale = sum(np.linalg.norm(t) for t in terms)
    return float(np.linalg.norm(sum(terms)) / scale) if scale > 0 else 0.0


def lqr(A, B, Q, R) -> LqrDesign:
    """LQR gain of ``x_dot = A x + B u`` for the weights Q (n x n, >= 0) and R (m x m, > 0).

    Raises ``ValueError`` (from the CARE solver) when no stabilising solution exists.

    Parameters
    ----------
    A : array_like, shape (n, n)
        System matrix [1/s].
    B : array_like, shape (n, m)
        Input matrix [state unit / (input unit s)].
    Q : array_like, shape (n, n)
        State weight (symmetric, >= 0) [1 / state unit^2].
    R : array_like, shape (m, m)
        Input weight (symmetric, > 0) [1 / input unit^2].

    Returns
    -------
    LqrDesign
        Gain K = R^-1 B^T P [input unit / state unit], P, the weights, the model, the CARE residual and
        the closed-loop eigenvalues [1/s].

    Raises
    ------
    ValueError
        No stabilising CARE solution.

    Examples
    --------
    Double integrator with Q = I, R = 1: K = [1, sqrt(3)]:

    >>> import numpy as np
    >>> from formation_ftc.design.lqr import lqr
    >>> d = lqr([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0]], np.eye(2), [[1.0]])
    >>> np.round(d.K, 6)
    array([[1.      , 1.732051]])
    >>> bool(np.all(d.closed_loop_eigenvalues.real < 0)), d.relative_residual < 1e-14
    (True, True)
    """
    A, B, Q, R = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (A, B, Q, R))
    sol = solve_care(A, B, Q, R)
    residual = care_relative_residual(sol.P, A, B, Q, R)
    return LqrDesign(sol.K, sol.P, Q, R, A, B, residual, sol.closed_loop_eigenvalues)


def cw_lqr(
    mean_motion: float, max_position_error, max_velocity_error, max_acceleration
) -> LqrDesign:
    """LQR gain for the Clohessy-Wiltshire model (acceleration input), weights by Bryson's rule.

    Parameters
    ----------
    mean_motion : float
        n of the circular reference orbit [rad/s] (>= 0; 0 gives three double integrators).
    max_position_error : float or array_like, shape (3,)
        Largest acceptable position error [m], one number or one per LVLH axis.
    max_velocity_error : float or array_like, shape (3,)
        Largest acceptable velocity error [m/s], one number or one per axis.
    max_acceleration : float or array_like, shape (3,)
        Largest acceptable commanded acceleration [m/s^2], one number or one per axis.

    Returns
    -------
    LqrDesign
        K (3, 6) [1/s^2 | 1/s]: the commanded acceleration is ``-K (q - q_d)`` [m/s^2]. Solved once
        per distinct input (cached; the arrays are read-only).

    Raises
    ------
    ValueError
        A negative or non-finite mean motion, or a bound that is not finite and > 0.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.design.lqr import cw_lqr
    >>> d = cw_lqr(0.0011, max_position_error=10.0, max_velocity_error=0.1, max_acceleration=1e-3)
    >>> d.K.shape
    (3, 6)
    >>> np.round(d.K[2, [2, 5]], 6)  # out-of-plane gains on z [1/s^2] and vz [1/s]
    array([9.9000e-05, 1.7251e-02])
    >>> bool(np.all(d.closed_loop_eigenvalues.real < 0))
    True
    """
    if not (np.isfinite(mean_motion) and mean_motion >= 0):
        raise ValueError(f"mean_motion = {mean_motion}: must be finite and >= 0 rad/s")
    pos = _positive(max_position_error, 3, "max_position_error")
    vel = _positive(max_velocity_error, 3, "max_velocity_error")
    acc = _positive(max_acceleration, 3, "max_acceleration")
    return _cw_lqr_cached(
        float(mean_motion), tuple(pos.tolist()), tuple(vel.tolist()), tuple(acc.tolist())
    )


@functools.lru_cache(maxsize=256)
def _cw_lqr_cached(
    mean_motion: float, pos: tuple[float, ...], vel: tuple[float, ...], acc: tuple[float, ...]
) -> LqrDesign:
    """The design of :func:`cw_lqr` for validated inputs, solved once per distinct input (a campaign or
    league builds the same controller for every run); its arrays are read-only since they are shared."""
    A, B = cw_matrices(mean_motion)
    Q, R = bryson_weights(np.asarray(pos + vel), np.asarray(acc))
    design = lqr(A, B, Q, R)
    for value in vars(design).values():
        if isinstance(value, np.ndarray):
            value.setflags(write=False)
    return design
