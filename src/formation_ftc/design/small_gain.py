"""Certified H-infinity norms and the small-gain bound of Azizi & Khorasani 2009, Theorem 1.

* :func:`hinf_norm` -- ``||G||_inf = sup_omega sigma_max(C (j omega I - A)^-1 B + D)`` as a certified
  bracket ``[lower, value]``:

  - the *estimate* comes from python-control's ``control.norm(sys, "inf")`` (Slycot's AB13DD when the
    optional ``slycot`` package is installed, otherwise python-control's Hamiltonian bisection), applied
    to a frequency- and state-scaled copy of the system (scaling by powers of two is exact and leaves the
    transfer function unchanged);
  - the *lower bound* is an exact evaluation ``sigma_max(G(j omega_peak))`` at frequencies found by the
    Bruinsma-Steinbuch iteration (imaginary eigenvalues of the Hamiltonian matrix);
  - the *upper bound* ``value`` is certified by the bounded-real (KYP) inequality: a symmetric X with
    ``M(X) = [[A^T X + X A + C^T C, X B + C^T D], [*, D^T D - gamma^2 I]] < 0`` and ``X > 0`` proves that
    A is Hurwitz and ``||G||_inf <= gamma`` (multiply M by ``[(j omega I - A)^-1 B; I]`` on both sides).
    X comes from a Riccati solve; the inequality is then re-checked in numpy with a margin that covers
    the rounding of M and of the symmetric eigenvalue solver.

  A matrix A with an eigenvalue on or right of the imaginary axis gives ``value = inf`` (the L2 gain of a
  system that is not internally stable is unbounded; an integrator is the simplest case).
* :func:`small_gain_margin` -- Theorem 1: ``S: X' = A X + U, Y = A X`` closed by ``U = Delta Y``;
  ``gamma_1 = ||A (s I - A)^-1||_inf`` and ``B_Delta = 1 / gamma_1`` with gamma_1 the certified upper
  bound, so ``||Delta|| < B_Delta`` never passes on an underestimated norm (gamma_1 = sqrt(2) for
  lambda0 = 2, lambda1 = 3, erratum E004-05 in docs/errata.md).

A frequency grid is *not* used here: a grid misses resonances between its points and outside its range
(a lightly damped mode at 5e3 rad/s reads 1.04 on a 1e-4 ... 1e3 rad/s grid instead of 50); the tests use a
grid only as a cross-check. Units: omega in rad/s; the norm has the units of output / input.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg

__all__ = [
    "sigma_max_response",
    "HinfNorm",
    "hinf_norm",
    "kyp_certificate",
    "SmallGainResult",
    "small_gain_margin",
    "hinf_method",
]

_EPS = np.finfo(float).eps


def sigma_max_response(A, B, C, D, omega) -> np.ndarray:
    """sigma_max of G(j omega) = C (j omega I - A)^-1 B + D for each omega [rad/s] (array).

    Parameters
    ----------
    A : array_like, shape (n, n)
        System matrix [1/s].
    B : array_like, shape (n, m)
        Input matrix.
    C : array_like, shape (p, n)
        Output matrix.
    D : array_like, shape (p, m)
        Feedthrough.
    omega : float or array_like
        Frequencies [rad/s].

    Returns
    -------
    numpy.ndarray, shape (len(omega),)
        sigma_max(G(j omega)) [output unit / input unit].

    Examples
    --------
    First-order lag ``1 / (s + 1)``: gain 1 at DC, 1/sqrt(2) at 1 rad/s:

    >>> import numpy as np
    >>> from formation_ftc.design.small_gain import sigma_max_response
    >>> np.round(sigma_max_response([[-1.0]], [[1.0]], [[1.0]], [[0.0]], [0.0, 1.0]), 6)
    array([1.      , 0.707107])
    """
    A, B, C, D = (np.asarray(x, dtype=complex) for x in (A, B, C, D))
    w = np.atleast_1d(np.asarray(omega, dtype=float))
    M = 1j * w[:, None, None] * np.eye(A.shape[0])[None] - A[None]
    G = C[None] @ np.linalg.solve(M, np.broadcast_to(B, (w.size,) + B.shape)) + D[None]
    return np.linalg.svd(G, compute_uv=False)[:, 0]


def hinf_method() -> str:
    """Name of the estimator python-control uses here (Slycot AB13DD if installed, else its bisection).

    Returns
    -------
    str
        The estimator's description.

    Examples
    --------
    >>> from formation_ftc.design.small_gain import hinf_method
    >>> hinf_method().startswith("python-control norm(sys, 'inf')")
    True
    """
    try:
        import slycot  # noqa: F401
    except ImportError:
        return (
            "python-control norm(sys, 'inf'), Hamiltonian bisection (scipy; slycot not installed)"
        )
    return "python-control norm(sys, 'inf') with Slycot AB13DD"


@dataclass(frozen=True)
class HinfNorm:
    """Certified H-infinity norm.

    Attributes
    ----------
    value : certified upper bound on ||G||_inf (``inf`` when A is not Hurwitz or nothing could be certified).
    lower : exact evaluation sigma_max(G(j omega_peak)) <= ||G||_inf (``inf`` when A is not Hurwitz).
    omega_peak : frequency of ``lower`` [rad/s] (``inf`` for the feedthrough D).
    estimate : python-control's value (nan if it failed).
    certified : True when ``value`` carries the KYP certificate (or is exact: no states, or A not Hurwitz).
    method : how the numbers were obtained (estimator, lower bound, certificate).
    reason : why the norm is infinite / uncertified; empty otherwise.
    """

    value: float
    lower: float
    omega_peak: float
    estimate: float
    certified: bool
    method: str
    reason: str = ""

    @property
    def relative_gap(self) -> float:
        """(value - lower) / value: the certified relative accuracy (0 for an exact or infinite norm)."""
        if not math.isfinite(self.value) or self.value == 0:
            return 0.0
        return (self.value - self.lower) / self.value

    def describe(self) -> str:
        """One line for a condition's detail: the value, the bracket, the method and the tolerance."""
        if not math.isfinite(self.value):
            return f"||G||_inf = inf: {self.reason}"
        if not self.certified:
            return f"||G||_inf NOT certified ({self.reason}); estimate {self.estimate:.6g}"
        return (
            f"||G||_inf <= {self.value:.8g} (certified: {self.method}); lower bound {self.lower:.8g} at "
            f"omega = {self.omega_peak:.4g} rad/s; relative gap {self.relative_gap:.1e}"
        )


def _pow2(x: float) -> float:
    return float(2.0 ** round(math.log2(x))) if x > 0 and math.isfinite(x) else 1.0


def _scaled(A, B, C):
    """Frequency scaling s = w0 s', state balancing and B/C equalisation, all by powers of two (exact).

    Returns (A', B', C', w0) with C' (s' I - A')^-1 B' = C (w0 s' I - A)^-1 B.
    """
    lam = np.abs(np.linalg.eigvals(A))
    lam = lam[lam > 0]
    w0 = _pow2(math.sqrt(lam.min() * lam.max())) if lam.size else 1.0
    As, Bs = A / w0, B / w0
    _, (scale, _) = scipy.linalg.matrix_balance(As, permute=False, separate=True)
    scale = np.asarray([_pow2(s) for s in scale])
    As = As * (1.0 / scale)[:, None] * scale[None, :]
    Bs = Bs / scale[:, None]
    Cs = C * scale[None, :]
    nb, nc = np.linalg.norm(Bs), np.linalg.norm(Cs)
    c = _pow2(math.sqrt(nc / nb)) if nb > 0 and nc > 0 else 1.0
    return As, Bs * c, Cs / c, w0


def _kyp_matrix(A, B, C, D, X, g2: float) -> np.ndarray:
    """``[[A^T X + X A + C^T C, X B + C^T D], [*, D^T D + g2 I]]``: the bounded-real matrix M(X) for
    ``g2 = -gamma^2``; of the element-wise ``|.|`` of every factor and ``g2 = gamma^2``, the matrix whose
    norm bounds the rounding error of forming M."""
    XB = X @ B + C.T @ D
    return np.block([[A.T @ X + X @ A + C.T @ C, XB], [XB.T, D.T @ D + g2 * np.eye(B.shape[1])]])


def kyp_certificate(A, B, C, D, gamma: float) -> tuple[bool, str]:
    """Bounded-real certificate of ``||G||_inf < gamma`` for G = (A, B, C, D), checked in numpy.

    Finds X from ``A^T X + X A + (X B + C^T D) R^-1 (B^T X + D^T C) + C^T C + e I = 0`` with
    ``R = gamma^2 I - D^T D`` and verifies ``lambda_max(M(X)) < -margin`` and ``lambda_min(X) > margin``,
    where the margins bound the floating-point error of forming M (element-wise |.| products times
    ``(n + m + 2) eps``) plus the eigenvalue solver's backward error. Returns (certified, detail).

    Parameters
    ----------
    A : array_like, shape (n, n)
        System matrix [1/s].
    B : array_like, shape (n, m)
        Input matrix.
    C : array_like, shape (p, n)
        Output matrix.
    D : array_like, shape (p, m)
        Feedthrough.
    gamma : float
        Candidate bound on ||G||_inf [output unit / input unit].

    Returns
    -------
    certified : bool
        Whether ``||G||_inf < gamma`` is proven.
    detail : str
        The checked eigenvalues, or why the certificate failed.

    Examples
    --------
    ``1 / (s + 1)`` has ||G||_inf = 1:

    >>> from formation_ftc.design.small_gain import kyp_certificate
    >>> kyp_certificate([[-1.0]], [[1.0]], [[1.0]], [[0.0]], gamma=1.01)[0]
    True
    >>> kyp_certificate([[-1.0]], [[1.0]], [[1.0]], [[0.0]], gamma=0.99)[0]
    False
    """
    A, B, C, D = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (A, B, C, D))
    n, m = A.shape[0], B.shape[1]
    R = gamma**2 * np.eye(m) - D.T @ D
    if np.linalg.eigvalsh(R).min() <= 0:
        return False, f"gamma = {gamma:.6g} <= sigma_max(D)"
    CC = C.T @ C
    base = max(float(np.linalg.norm(CC, 2)), float(np.linalg.norm(A, 2)) * 1e-8, 1e-300)
    last = "Riccati solve failed"
    for e_rel in (1e-6, 1e-8, 1e-10, 1e-12):
        Q = CC + e_rel * base * np.eye(n)
        try:
            with warnings.catch_warnings(action="ignore"):
                X = scipy.linalg.solve_continuous_are(A, B, Q, -R, s=C.T @ D)
        except (np.linalg.LinAlgError, ValueError) as exc:
            last = f"Riccati solve failed ({str(exc)[:60]})"
            continue
        X = (X + X.T) / 2
        if not np.all(np.isfinite(X)):
            continue
        M = _kyp_matrix(A, B, C, D, X, -(gamma**2))
        Mabs = _kyp_matrix(np.abs(A), np.abs(B), np.abs(C), np.abs(D), np.abs(X), gamma**2)
        k = n + m
        margin = (k + 2) * _EPS * np.linalg.norm(Mabs, 2) + 10 * k * _EPS * np.linalg.norm(M, 2)
        lmax = float(np.linalg.eigvalsh(M).max())
        xmin = float(np.linalg.eigvalsh(X).min())
        if lmax < -margin and xmin > 10 * n * _EPS * np.linalg.norm(X, 2):
            return True, (
                f"KYP: lambda_max(M) = {lmax:.3g} < -{margin:.2g} (rounding bound), "
                f"lambda_min(X) = {xmin:.3g} > 0"
            )
        last = f"KYP check failed: lambda_max(M) = {lmax:.3g} (margin {margin:.2g}), lambda_min(X) = {xmin:.3g}"
    return False, last


def _hamiltonian(A, B, C, D, g):
    m = B.shape[1]
    Rinv = np.linalg.inv(g * g * np.eye(m) - D.T @ D)
    Ah = A + B @ Rinv @ D.T @ C
    return np.block(
        [[Ah, B @ Rinv @ B.T], [-C.T @ (np.eye(C.shape[0]) + D @ Rinv @ D.T) @ C, -Ah.T]]
    )


def _lower_bound(A, B, C, D, sd, rtol):
    """Bruinsma-Steinbuch iteration: exact sigma_max evaluations converging to the peak (scaled system);
    ``sd`` = sigma_max(D)."""
    eig = np.linalg.eigvals(A)
    cand = np.unique(np.concatenate([[0.0], np.abs(eig.imag), np.abs(eig)]))
    s = sigma_max_response(A, B, C, D, cand)
    i = int(np.argmax(s))
    gl, wp = float(s[i]), float(cand[i])
    if sd > gl:
        gl, wp = sd, math.inf
    for _ in range(60):
        g = (1 + 2 * rtol) * gl if gl > 0 else 1e-300
        if g <= sd:
            break
        ev = np.linalg.eigvals(_hamiltonian(A, B, C, D, g))
        near = ev[(np.abs(ev.real) <= 1e-6 * np.maximum(1.0, np.abs(ev))) & (ev.imag >= 0)]
        ws = np.sort(np.abs(near.imag))
        if ws.size == 0:
            break
        trial = np.concatenate(
            [ws, np.sqrt(ws[:-1] * ws[1:]) if ws.size > 1 else [], (ws[:-1] + ws[1:]) / 2]
        )
        st = sigma_max_response(A, B, C, D, trial)
        j = int(np.argmax(st))
        if st[j] <= gl * (1 + rtol / 10):
            break
        gl, wp = float(st[j]), float(trial[j])
    return gl, wp


def hinf_norm(A, B, C, D=None, rtol: float = 1e-6) -> HinfNorm:
    """Certified H-infinity norm of ``G(s) = C (s I - A)^-1 B + D`` (see the module docstring).

    Parameters
    ----------
    A : array_like, shape (n, n)
        System matrix [1/s].
    B : array_like, shape (n, m)
        Input matrix.
    C : array_like, shape (p, n)
        Output matrix.
    D : array_like, shape (p, m), optional
        Feedthrough (defaults to zero).
    rtol : float, optional
        Target relative gap between the certified upper bound and the exact lower bound [-].

    Returns
    -------
    HinfNorm
        ``value`` is the certified upper bound [output unit / input unit] (use it in a small-gain test);
        ``inf`` with a reason when A is not Hurwitz or when no bound could be certified
        (``certified = False``).

    Raises
    ------
    ValueError
        Inconsistent shapes or non-finite matrices.

    Examples
    --------
    >>> from formation_ftc.design.small_gain import hinf_norm
    >>> h = hinf_norm([[0.0, 1.0], [-2.0, -3.0]], [[0.0], [1.0]], [[1.0, 0.0]])  # 1 / (s^2 + 3 s + 2)
    >>> round(h.value, 5), round(h.lower, 5), h.certified
    (0.5, 0.5, True)
    >>> hinf_norm([[0.0]], [[1.0]], [[1.0]]).value  # an integrator: not internally stable
    inf
    """
    A, B, C = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (A, B, C))
    n = A.shape[0]
    D = np.zeros((C.shape[0], B.shape[1])) if D is None else np.atleast_2d(np.asarray(D, float))
    if (
        A.shape != (n, n)
        or B.shape[0] != n
        or C.shape[1] != n
        or D.shape != (C.shape[0], B.shape[1])
    ):
        raise ValueError(f"inconsistent shapes A{A.shape}, B{B.shape}, C{C.shape}, D{D.shape}")
    if not all(np.all(np.isfinite(x)) for x in (A, B, C, D)):
        raise ValueError("state-space matrices must be finite")
    sd = float(np.linalg.svd(D, compute_uv=False)[0]) if D.size else 0.0
    if n == 0 or not np.any(B) or not np.any(C):
        return HinfNorm(sd, sd, math.inf, sd, True, "exact: G = D (no state reaches the output)")
    eig = np.linalg.eigvals(A)
    if np.any(eig.real >= 0):
        bad = np.round(eig[eig.real >= 0], 6).tolist()
        reason = (
            f"A is not Hurwitz (eigenvalue(s) {bad} with Re >= 0): the system is not internally "
            "stable and its L2 gain is unbounded"
        )
        return HinfNorm(math.inf, math.inf, math.nan, math.inf, True, "eigenvalues of A", reason)
    As, Bs, Cs, w0 = _scaled(A, B, C)
    try:
        import control

        with warnings.catch_warnings(action="ignore"):
            scaled = control.ss(As, Bs, Cs, D)
            est = float(control.norm(scaled, "inf", tol=min(rtol / 10, 1e-8), print_warning=False))
    except Exception:  # noqa: BLE001 - any estimator failure leaves the certificate to decide
        est = math.nan
    gl, wp = _lower_bound(As, Bs, Cs, D, sd, rtol)
    method = f"{hinf_method()}; bounded-real (KYP) inequality re-checked in numpy"
    tries = [gl * (1 + rtol)]
    if math.isfinite(est) and est > gl * (1 + rtol):
        tries.append(est * (1 + rtol))
    tries += [gl * (1 + rtol * 10**k) for k in range(1, 5)]
    detail = ""
    for g in sorted(set(tries)):
        ok, detail = kyp_certificate(As, Bs, Cs, D, g)
        if ok:
            return HinfNorm(float(g), gl, wp * w0, est, True, method)
    reason = f"no bound up to {max(tries):.6g} could be certified ({detail})"
    return HinfNorm(math.inf, gl, wp * w0, est, False, method, reason)


@dataclass(frozen=True)
class SmallGainResult:
    """gamma_1 [-] (certified upper bound), its peak frequency [rad/s], and B_Delta = 1/gamma_1.

    ``norm`` holds the full :class:`HinfNorm` (bracket, method, tolerance) for the condition's detail.
    """

    gamma1: float
    omega_peak: float
    b_delta: float
    norm: HinfNorm | None = None

    @property
    def certificate(self) -> str:
        """How gamma_1 was obtained and its accuracy (one line)."""
        return self.norm.describe() if self.norm is not None else ""

    def holds(self, delta_norm: float) -> bool:
        """Theorem 1 sufficient condition ||Delta|| < B_Delta (False when gamma_1 is not certified)."""
        if self.norm is not None and not self.norm.certified:
            return False
        return bool(delta_norm < self.b_delta)


def small_gain_margin(A) -> SmallGainResult:
    """Azizi2009 Theorem 1: gamma_1 = ||A (s I - A)^-1||_inf (certified upper bound), B_Delta = 1/gamma_1.

    Parameters
    ----------
    A : array_like, shape (n, n)
        The nominal error dynamics, e.g. :func:`formation_ftc.design.flfr.error_dynamics_matrix`
        [1/s, 1/s^2].

    Returns
    -------
    SmallGainResult
        gamma_1 [-], its peak frequency [rad/s] and B_Delta = 1 / gamma_1 [-].

    Examples
    --------
    lambda0 = 2, lambda1 = 3 gives gamma_1 = sqrt(2) (E004-05):

    >>> from formation_ftc.design.flfr import error_dynamics_matrix
    >>> from formation_ftc.design.small_gain import small_gain_margin
    >>> r = small_gain_margin(error_dynamics_matrix(2.0, 3.0))
    >>> round(r.gamma1, 5), round(r.b_delta, 5)
    (1.41421, 0.70711)
    >>> r.holds(0.5), r.holds(0.8)
    (True, False)
    """
    n = np.shape(A)[0]
    res = hinf_norm(A, np.eye(n), A, np.zeros((n, n)))
    b_delta = 1.0 / res.value if res.value > 0 else math.inf
    return SmallGainResult(gamma1=res.value, omega_peak=res.omega_peak, b_delta=b_delta, norm=res)
