"""Kalman filter design for relative navigation: discrete model of a sampled linear system with white
acceleration noise, and the steady-state (Riccati) filter.

A continuous model ``x' = A x + B a + G w`` (``w`` white, power spectral density ``q`` [(m/s^2)^2/Hz]
per axis), with the input ``a`` held over each step of length ``dt`` and a measurement ``y_k = x_k + v_k``
of covariance ``R`` at every step, becomes::

    x_{k+1} = Phi x_k + Gamma a_k + w_k,   w_k ~ N(0, Qd),
    Phi = e^{A dt},  Gamma = int_0^dt e^{A s} ds B,  Qd = int_0^dt e^{A s} G q G^T e^{A^T s} ds

(``Qd`` by Van Loan's method). The filter's steady-state predicted covariance ``P`` solves the discrete
algebraic Riccati equation ``P = Phi P Phi^T - Phi P (P + R)^{-1} P Phi^T + Qd`` (full-state
measurement ``H = I``); its gain is ``K = P (P + R)^{-1}``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from formation_ftc.core.integrators import zoh_discretize

__all__ = ["DiscreteModel", "discrete_model", "steady_state_kalman", "dare_relative_residual"]


@dataclass(frozen=True)
class DiscreteModel:
    """``x_{k+1} = phi x_k + gamma a_k + w_k``, ``w_k ~ N(0, qd)`` (see module docstring)."""

    phi: np.ndarray  # (n, n)
    gamma: np.ndarray  # (n, m)
    qd: np.ndarray  # (n, n)


def discrete_model(A, B, G, q: float, dt: float) -> DiscreteModel:
    """Exact discretisation of ``x' = A x + B a + G w`` over a step ``dt`` [s] with ``a`` held and
    ``w`` white of spectral density ``q`` per channel (Van Loan).

    Parameters
    ----------
    A : array_like, shape (n, n)
        State matrix of the continuous model.
    B : array_like, shape (n, m)
        Input matrix (the held input, e.g. the commanded acceleration [m/s^2]).
    G : array_like, shape (n, p)
        Noise input matrix.
    q : float
        Power spectral density of each noise channel (>= 0).
    dt : float
        Step [s] (> 0).

    Returns
    -------
    DiscreteModel
        ``phi``, ``gamma`` and the process-noise covariance ``qd`` (symmetric, >= 0).

    Examples
    --------
    >>> import numpy as np
    >>> m = discrete_model([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0]], [[0.0], [1.0]], q=2.0, dt=0.5)
    >>> np.allclose(m.qd, 2.0 * np.array([[0.5**3 / 3, 0.5**2 / 2], [0.5**2 / 2, 0.5]]))
    True
    """
    A, G = np.asarray(A, dtype=float), np.asarray(G, dtype=float)
    if not (dt > 0 and np.isfinite(dt)) or not (q >= 0 and np.isfinite(q)):
        raise ValueError(f"discrete_model: dt = {dt} s must be > 0 and q = {q} >= 0")
    phi, gamma = zoh_discretize(A, B, dt)
    n = A.shape[0]
    # Van Loan: expm([[-A, G q G^T], [0, A^T]] dt) = [[., Phi^-1 Qd], [0, Phi^T]]
    M = np.block([[-A, q * G @ G.T], [np.zeros((n, n)), A.T]])
    E = scipy.linalg.expm(M * dt)
    qd = E[n:, n:].T @ E[:n, n:]
    return DiscreteModel(phi, gamma, 0.5 * (qd + qd.T))


def steady_state_kalman(phi, qd, R) -> tuple[np.ndarray, np.ndarray]:
    """Steady-state predicted covariance ``P`` and gain ``K = P (P + R)^{-1}`` of the filter with a
    full-state measurement of covariance ``R`` (``scipy.linalg.solve_discrete_are``).

    Parameters
    ----------
    phi : array_like, shape (n, n)
        State transition over one step.
    qd : array_like, shape (n, n)
        Process-noise covariance per step.
    R : array_like, shape (n, n)
        Measurement-noise covariance (positive definite).

    Returns
    -------
    P : ndarray, shape (n, n)
        Predicted (a priori) error covariance in steady state.
    K : ndarray, shape (n, n)
        Measurement-update gain.

    Examples
    --------
    A random walk measured directly: ``P = (q + sqrt(q^2 + 4 q r)) / 2``.

    >>> P, K = steady_state_kalman([[1.0]], [[1.0]], [[1.0]])
    >>> round(float(P[0, 0]), 12) == round((1 + 5**0.5) / 2, 12)
    True
    """
    phi, qd, R = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (phi, qd, R))
    P = scipy.linalg.solve_discrete_are(phi.T, np.eye(len(phi)), qd, R)
    K = P @ np.linalg.inv(P + R)
    return P, K


def dare_relative_residual(P, phi, qd, R) -> float:
    """Relative residual of the filter Riccati equation (see module docstring) at ``P``.

    Parameters
    ----------
    P : array_like, shape (n, n)
        Candidate predicted covariance.
    phi, qd, R : array_like, shape (n, n)
        Transition, process-noise and measurement-noise matrices of :func:`steady_state_kalman`.

    Returns
    -------
    float
        ``||P - (phi P phi^T - phi P (P + R)^-1 P phi^T + qd)|| / ||P||`` (Frobenius) [-].

    Examples
    --------
    >>> P, _ = steady_state_kalman([[1.0]], [[1.0]], [[1.0]])
    >>> dare_relative_residual(P, [[1.0]], [[1.0]], [[1.0]]) < 1e-12
    True
    """
    P, phi, qd, R = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (P, phi, qd, R))
    rhs = phi @ P @ phi.T - phi @ P @ np.linalg.solve(P + R, P) @ phi.T + qd
    return float(np.linalg.norm(P - rhs) / max(float(np.linalg.norm(P)), 1e-300))
