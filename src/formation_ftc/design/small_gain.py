"""Small-gain bounds: H-infinity norms on a frequency grid (SPEC.md 0.5; Azizi2009 Theorem 1).

* :func:`hinf_norm_grid` -- ``sup_omega sigma_max(C (j omega I - A)^-1 B + D)`` on a log grid
  (1e-4 ... 1e3 rad/s, >= 2e4 points by default), refined by a bounded scalar search around the grid
  peak; omega = 0 and omega -> inf are included (DC gain and D).
* :func:`small_gain_margin` -- Azizi2009 Theorem 1: ``S: X' = A X + U, Y = A X`` closed by
  ``U = Delta Y``; ``gamma_1 = sup sigma_max[A (j omega I - A)^-1]`` and ``B_Delta = 1 / gamma_1``
  (E004-05: gamma_1 = sqrt(2) for lambda0 = 2, lambda1 = 3).

python-control's ``hinfnorm``/``linfnorm`` needs slycot, which is not installed; the grid + refinement
here is checked against closed-form norms in the tests.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.optimize

__all__ = ["sigma_max_response", "hinf_norm_grid", "SmallGainResult", "small_gain_margin"]


def sigma_max_response(A, B, C, D, omega) -> np.ndarray:
    """sigma_max of G(j omega) = C (j omega I - A)^-1 B + D for each omega [rad/s] (array)."""
    A = np.asarray(A, dtype=complex)
    B = np.asarray(B, dtype=complex)
    C = np.asarray(C, dtype=complex)
    D = np.asarray(D, dtype=complex)
    w = np.atleast_1d(np.asarray(omega, dtype=float))
    n = A.shape[0]
    eye = np.eye(n)
    M = 1j * w[:, None, None] * eye[None] - A[None]
    G = C[None] @ np.linalg.solve(M, np.broadcast_to(B, (w.size,) + B.shape)) + D[None]
    return np.linalg.svd(G, compute_uv=False)[:, 0]


def hinf_norm_grid(A, B, C, D=None, w_min: float = 1e-4, w_max: float = 1e3, n_points: int = 20000
                   ) -> tuple[float, float]:
    """(gamma, omega_peak): H-infinity norm of a stable LTI system on a log grid, refined.

    Raises ``ValueError`` if A is not Hurwitz (the norm is then infinite / not an L2 gain).
    """
    A = np.asarray(A, dtype=float)
    C = np.asarray(C, dtype=float)
    B = np.asarray(B, dtype=float)
    D = np.zeros((C.shape[0], B.shape[1])) if D is None else np.asarray(D, dtype=float)
    eig = np.linalg.eigvals(A)
    if np.any(eig.real >= 0):
        raise ValueError(f"A is not Hurwitz (eigenvalues {eig}); the small-gain norm is not finite")
    w = np.concatenate([[0.0], np.logspace(np.log10(w_min), np.log10(w_max), n_points)])
    s = sigma_max_response(A, B, C, D, w)
    i = int(np.argmax(s))
    gamma, w_peak = float(s[i]), float(w[i])
    # omega -> infinity: sigma_max(D)
    s_inf = float(np.linalg.svd(D, compute_uv=False)[0]) if D.size else 0.0
    if s_inf > gamma:
        return s_inf, float("inf")
    if 0 < i < w.size - 1:
        lo, hi = np.log10(max(w[i - 1], w_min * 0.1)), np.log10(w[i + 1])
        res = scipy.optimize.minimize_scalar(
            lambda lw: -sigma_max_response(A, B, C, D, 10.0**lw)[0], bounds=(lo, hi), method="bounded",
            options={"xatol": 1e-12})
        if -res.fun > gamma:
            gamma, w_peak = float(-res.fun), float(10.0**res.x)
    return gamma, w_peak


@dataclass(frozen=True)
class SmallGainResult:
    """gamma_1 [-], its peak frequency [rad/s], and the admissible perturbation bound B_Delta = 1/gamma_1."""

    gamma1: float
    omega_peak: float
    b_delta: float

    def holds(self, delta_norm: float) -> bool:
        """Theorem 1 sufficient condition ||Delta|| < B_Delta."""
        return bool(delta_norm < self.b_delta)


def small_gain_margin(A) -> SmallGainResult:
    """Azizi2009 Theorem 1 (E004-05): gamma_1 = sup_omega sigma_max[A (j omega I - A)^-1]."""
    A = np.asarray(A, dtype=float)
    n = A.shape[0]
    gamma, w = hinf_norm_grid(A, np.eye(n), A, np.zeros((n, n)))
    return SmallGainResult(gamma1=gamma, omega_peak=w, b_delta=1.0 / gamma)
