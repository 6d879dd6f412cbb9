"""LMI synthesis of the iterative-learning-observer gains (Gui et al. 2022, Theorem 1 and Remark 1).

Finds ``P = P^T > 0``, ``Y`` and ``L2`` such that

* (8)   ``P A + A^T P - Y C - C^T Y^T < 0``                       (observer Lyapunov inequality)
* (27)  ``[[-lam I, H^T P - L2 C], [*, -I]] < 0``                 (Schur relaxation of (9) ``H^T P = L2 C``)
* disk  ``[[-r P, P A - Y C - c P], [*, -r P]] < 0``             (all eig(A - L1 C) in the disk S(c, r))

and returns ``L1 = P^-1 Y`` (Theorem 1), with cvxpy and the CLARABEL interior-point solver (SCS as a
fallback). Strict inequalities are imposed as ``<= -eps I`` (eps = 1e-6); (27) uses the
margin ``min(eps, lam / 10)`` because its own diagonal is only ``-lam = -1e-8``.

Homogeneity (E002-06): (8), (27) and the disk LMI are homogeneous in (P, Y, L2) -- if
(P, Y, L2) is a solution, so is (s P, s Y, s L2) for any s >= 1 (margins aside), and L1 = P^-1 Y does not
change. The solver's scaling of P is therefore arbitrary, and it fixes the *magnitude* of L2 that the
learning law uses. To make the result reproducible we add the normalisation ``P >= I`` and minimise
``trace(P)``; :func:`rescale_design` applies the free scale factor (e.g. to match the printed L2 ~ 456).

An infeasible problem raises :class:`DesignInfeasible` naming the conflicting constraint(s) (found by
re-solving with each constraint group dropped) and the solver status. Offline code; never called in the
time loop.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from formation_ftc.errors import InputError, require_extra

__all__ = [
    "DesignInfeasible",
    "IloLmiDesign",
    "design_ilo_gains",
    "ilo_lmi_residuals",
    "rescale_design",
    "rounding_margin",
    "CONSTRAINT_NAMES",
]

#: Human-readable names of the constraint groups (used in error messages and residual reports).
CONSTRAINT_NAMES = {
    "lyapunov_8": "(8) P A + A^T P - Y C - C^T Y^T < 0",
    "schur_27": "(27) [[-lam I, H^T P - L2 C], [*, -I]] < 0 (relaxed (9))",
    "disk": "disk pole region S(c, r): [[-r P, P A - Y C - c P], [*, -r P]] < 0",
    "normalisation": "normalisation P >= I (fixes the free scale of the homogeneous LMIs)",
}


class DesignInfeasible(InputError):
    """The LMI problem has no solution. ``constraints`` names the conflicting groups, ``status`` is the
    solver status (e.g. ``'infeasible'``)."""

    def __init__(
        self, message: str, constraints: tuple[str, ...] = (), status: str = "", solver: str = ""
    ):
        super().__init__(message)
        self.constraints = constraints
        self.status = status
        self.solver = solver


@dataclass(frozen=True)
class IloLmiDesign:
    """Result of :func:`design_ilo_gains`.

    Attributes
    ----------
    P : (n, n) Lyapunov matrix; Y : (n, p); L2 : (m, p) learning gain; L1 : (n, p) = P^-1 Y [1/s].
    lam : the small scalar of (27); disk_center, disk_radius : pole region S(c, r) [1/s].
    residuals : see :func:`ilo_lmi_residuals`.
    poles : eig(A - L1 C) [1/s].
    solver, status : solver used and its final status.
    """

    P: np.ndarray
    Y: np.ndarray
    L1: np.ndarray
    L2: np.ndarray
    lam: float
    disk_center: float
    disk_radius: float
    residuals: dict[str, float] = field(default_factory=dict)
    poles: np.ndarray = field(default_factory=lambda: np.zeros(0))
    solver: str = ""
    status: str = ""


def _sym(M):
    return (M + M.T) / 2


def _lmi_matrices(A, C, H, P, Y, L2, lam, c, r, bmat):
    """Matrices of (8), (9), (27) and the disk LMI; ``bmat``: ``np.block`` or ``cvxpy.bmat``."""
    n, m = A.shape[0], H.shape[1]
    M8 = P @ A + A.T @ P - Y @ C - C.T @ Y.T  # Gui2022 eq. (8)
    X = H.T @ P - L2 @ C  # eq. (9)
    M27 = bmat([[-lam * np.eye(m), X], [X.T, -np.eye(n)]])  # eq. (27)
    D = P @ A - Y @ C - c * P
    MD = bmat([[-r * P, D], [D.T, -r * P]])  # D-stability, disk S(c, r)
    return M8, X, M27, MD


def rounding_margin(M) -> float:
    """Bound on the floating-point error of the extreme eigenvalues of a symmetric matrix M.

    ``10 n eps ||M||_2`` covers the backward error of the symmetric eigenvalue solver and the rounding
    of forming M from products of the design matrices; a definiteness claim ``lambda_max(M) < 0`` is
    only *verified* when ``lambda_max(M) < -rounding_margin(M)``.

    Parameters
    ----------
    M : array_like, shape (n, n)
        Symmetric matrix (any units).

    Returns
    -------
    float
        The margin, in the units of M.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.design.lmi import rounding_margin
    >>> f"{rounding_margin(np.diag([-1.0, -2.0])):.3e}"  # 10 * 2 * eps * 2
    '8.882e-15'
    """
    M = np.atleast_2d(np.asarray(M, dtype=float))
    return float(10 * M.shape[0] * np.finfo(float).eps * np.linalg.norm(M, 2))


def ilo_lmi_residuals(
    A, C, H, P, Y, L2, lam: float = 1e-8, disk_center: float = -5.0, disk_radius: float = 2.0
) -> dict[str, float]:
    """Numerical certificate of a candidate (P, Y, L2), recomputed in numpy from the matrices themselves.

    Parameters
    ----------
    A : array_like, shape (n, n)
        System matrix [1/s].
    C : array_like, shape (p, n)
        Output matrix [-].
    H : array_like, shape (n, m)
        Fault distribution matrix [-].
    P : array_like, shape (n, n)
        Candidate Lyapunov matrix [-].
    Y : array_like, shape (n, p)
        Candidate ``P L1`` [1/s].
    L2 : array_like, shape (m, p)
        Candidate learning gain [-].
    lam : float, optional
        The small positive scalar of (27) [-].
    disk_center, disk_radius : float, optional
        Pole region S(c, r): centre c and radius r [1/s].

    Returns
    -------
    dict
        ``max_eig_8`` (< 0 required), ``max_eig_27`` (< 0), ``max_abs_9`` = max|H^T P - L2 C|
        (0 for (9) exactly), ``max_eig_disk`` (< 0), ``min_eig_P`` (> 0), ``max_pole_distance`` =
        max |eig(A - L1 C) - c| (< r), ``max_pole_real`` [1/s], and ``tol_8``, ``tol_27``, ``tol_disk``,
        ``tol_P``: the rounding margins (:func:`rounding_margin`) each eigenvalue must clear for the
        inequality to count as verified.

    Examples
    --------
    A double integrator with P = I, L1 = 4 I (poles -4, -4, inside S(-5, 2)) and L2 with H^T P = L2 C:

    >>> import numpy as np
    >>> from formation_ftc.design.lmi import ilo_lmi_residuals
    >>> A, C, H = np.array([[0.0, 1.0], [0.0, 0.0]]), np.eye(2), np.array([[0.0], [1.0]])
    >>> r = ilo_lmi_residuals(A, C, H, P=np.eye(2), Y=4.0 * np.eye(2), L2=np.array([[0.0, 1.0]]))
    >>> round(r["max_eig_8"], 6), r["max_abs_9"], round(r["max_eig_disk"], 6), r["max_pole_distance"]
    (-7.0, 0.0, -0.381966, 1.0)
    """
    A, C, H, P, Y, L2 = (np.asarray(x, dtype=float) for x in (A, C, H, P, Y, L2))
    M8, X, M27, MD = _lmi_matrices(A, C, H, P, Y, L2, lam, disk_center, disk_radius, np.block)
    M8 = _sym(M8)
    L1 = np.linalg.solve(P, Y)
    poles = np.linalg.eigvals(A - L1 @ C)
    return {
        "tol_8": rounding_margin(M8),
        "tol_27": rounding_margin(M27),
        "tol_disk": rounding_margin(MD),
        "tol_P": rounding_margin(P),
        "max_eig_8": float(np.max(np.linalg.eigvalsh(M8))),
        "max_eig_27": float(np.max(np.linalg.eigvalsh(_sym(M27)))),
        "max_abs_9": float(np.max(np.abs(X))),
        "max_eig_disk": float(np.max(np.linalg.eigvalsh(_sym(MD)))),
        "min_eig_P": float(np.min(np.linalg.eigvalsh(_sym(P)))),
        "max_pole_distance": float(np.max(np.abs(poles - disk_center))),
        "max_pole_real": float(np.max(poles.real)),
    }


def _build_problem(A, C, H, lam, c, r, eps, groups):
    cp = require_extra("cvxpy", "lmi", "LMI design (formation_ftc.design.lmi)")

    n, p, m = A.shape[0], C.shape[0], H.shape[1]
    P = cp.Variable((n, n), symmetric=True)
    Y = cp.Variable((n, p))
    L2 = cp.Variable((m, p))
    M8, _, M27, MD = _lmi_matrices(A, C, H, P, Y, L2, lam, c, r, cp.bmat)
    # group -> (M, margin) of the strict LMI M < 0 imposed as M <= -margin I
    lmis = {"lyapunov_8": (M8, eps), "schur_27": (M27, min(eps, lam / 10)), "disk": (MD, eps)}
    cons = [_sym(M) << -e * np.eye(M.shape[0]) for g, (M, e) in lmis.items() if g in groups]
    cons.append(P >> (np.eye(n) if "normalisation" in groups else eps * np.eye(n)))
    prob = cp.Problem(cp.Minimize(cp.trace(P)), cons)
    return prob, P, Y, L2


def _solve(prob, solver):
    """Solve with ``solver`` (or CLARABEL, then SCS); return (status, solver_name)."""
    cp = require_extra("cvxpy", "lmi", "LMI design (formation_ftc.design.lmi)")

    order = [solver] if solver else ["CLARABEL", "SCS"]
    installed = set(cp.installed_solvers())
    last = ("solver_error", order[-1])
    for name in order:
        if name not in installed:
            last = (f"solver {name} not installed", name)
            continue
        try:
            kwargs = {"eps": 1e-9, "max_iters": 200000} if name == "SCS" else {}
            prob.solve(solver=name, **kwargs)
        except (KeyboardInterrupt, SystemExit):  # pragma: no cover
            raise
        except BaseException as exc:  # noqa: BLE001 - SolverError, or a Rust panic of CLARABEL
            # (pyo3 PanicException derives from BaseException; seen on near-infeasible disk LMIs)
            last = (f"solver_error: {type(exc).__name__}: {str(exc)[:120]}", name)
            continue
        status = str(prob.status)
        if status in ("optimal", "infeasible", "unbounded") or name == order[-1]:
            return status, name
        last = (status, name)
    return last


def design_ilo_gains(
    A,
    C,
    H,
    *,
    lam: float = 1e-8,
    disk_center: float = -5.0,
    disk_radius: float = 2.0,
    eps: float = 1e-6,
    solver: str | None = None,
) -> IloLmiDesign:
    """Solve (8), (27) and the disk LMI (Gui2022 Remark 1, design steps (3)-(4)); ``L1 = P^-1 Y``.

    Parameters
    ----------
    A : array_like, shape (n, n)
        System matrix [1/s].
    C : array_like, shape (p, n)
        Output matrix [-].
    H : array_like, shape (n, m)
        Fault distribution matrix [-].
    lam : float, optional
        The small positive scalar of (27) (paper: 1e-8) [-].
    disk_center, disk_radius : float, optional
        The pole region S(c, r): centre c (< 0) and radius r (> 0) [1/s].
    eps : float, optional
        Margin of the strict inequalities [-].
    solver : str, optional
        cvxpy solver name; default CLARABEL with SCS as fallback.

    Returns
    -------
    IloLmiDesign
        P, Y, L1 = P^-1 Y [1/s], L2 [-], the residual certificate of :func:`ilo_lmi_residuals` and the
        poles eig(A - L1 C) [1/s].

    Raises
    ------
    DesignInfeasible
        No solution; the message names the constraint(s) whose removal makes the problem feasible and
        the solver status.
    ValueError
        Bad arguments (radius <= 0, lam <= 0, shapes).

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.design.lmi import design_ilo_gains
    >>> A, C, H = np.array([[0.0, 1.0], [0.0, 0.0]]), np.eye(2), np.array([[0.0], [1.0]])
    >>> d = design_ilo_gains(A, C, H, disk_center=-5.0, disk_radius=2.0)
    >>> d.status
    'optimal'
    >>> bool(np.all(np.abs(d.poles - d.disk_center) < d.disk_radius))  # poles inside S(-5, 2)
    True
    >>> d.residuals["max_eig_8"] < -d.residuals["tol_8"]  # (8) verified in numpy
    True
    """
    A, C, H = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (A, C, H))
    if not (disk_radius > 0):
        raise ValueError(f"disk_radius must be > 0 1/s, got {disk_radius}")
    if not (lam > 0):
        raise ValueError(f"lam must be > 0, got {lam}")
    n = A.shape[0]
    if A.shape != (n, n) or C.shape[1] != n or H.shape[0] != n:
        raise ValueError(f"inconsistent shapes A{A.shape}, C{C.shape}, H{H.shape}")
    all_groups = ("lyapunov_8", "schur_27", "disk", "normalisation")

    def attempt(groups):  # ((status, solver), (P, Y, L2)) of the problem of these groups
        prob, *variables = _build_problem(A, C, H, lam, disk_center, disk_radius, eps, groups)
        return _solve(prob, solver), variables

    (status, used), (P, Y, L2) = attempt(all_groups)
    region = f"S({disk_center:g}, {disk_radius:g})"
    if status not in ("optimal", "optimal_inaccurate"):
        # the groups whose removal alone makes the problem feasible
        without = [tuple(x for x in all_groups if x != g) for g in all_groups]
        solved = [attempt(groups)[0][0] in ("optimal", "optimal_inaccurate") for groups in without]
        culprits = [g for g, ok in zip(all_groups, solved, strict=True) if ok]
        names = (
            "; ".join(CONSTRAINT_NAMES[g].replace("S(c, r)", region) for g in culprits)
            or "no single constraint (the combination of (8), (27) and the disk region is infeasible)"
        )
        raise DesignInfeasible(
            f"ILO gain LMI is infeasible (solver {used}, status '{status}'); conflicting constraint(s), "
            f"each of which alone makes the problem feasible when removed: {names}. Pole region {region}: centre {disk_center:g} 1/s, radius {disk_radius:g} 1/s.",
            constraints=tuple(culprits),
            status=status,
            solver=used,
        )
    Pv, Yv, L2v = _sym(np.asarray(P.value)), np.asarray(Y.value), np.asarray(L2.value)
    res = ilo_lmi_residuals(A, C, H, Pv, Yv, L2v, lam, disk_center, disk_radius)
    # each lambda_max must clear its rounding margin, lambda_min(P) its own
    strict = (("max_eig_8", "tol_8"), ("max_eig_27", "tol_27"), ("max_eig_disk", "tol_disk"))
    bad = [k for k, t in strict if not res[k] < -res[t]]
    if not res["min_eig_P"] > res["tol_P"]:
        bad.append("min_eig_P")
    if bad:
        raise DesignInfeasible(
            f"ILO gain LMI: solver {used} returned status '{status}' but the solution fails the numerical "
            f"check of {', '.join(bad)} ({', '.join(f'{k} = {res[k]:.3g}' for k in bad)})",
            constraints=tuple(bad),
            status=status,
            solver=used,
        )
    L1 = np.linalg.solve(Pv, Yv)
    return IloLmiDesign(
        P=Pv,
        Y=Yv,
        L1=L1,
        L2=L2v,
        lam=lam,
        disk_center=disk_center,
        disk_radius=disk_radius,
        residuals=res,
        poles=np.linalg.eigvals(A - L1 @ C),
        solver=used,
        status=status,
    )


def rescale_design(design: IloLmiDesign, factor: float, A, C, H) -> IloLmiDesign:
    """Apply the free scale of the homogeneous LMIs: (P, Y, L2) -> factor * (P, Y, L2); L1 unchanged.

    ``factor >= 1`` keeps every ``-eps I`` margin; residuals are recomputed.

    Parameters
    ----------
    design : IloLmiDesign
        A design from :func:`design_ilo_gains`.
    factor : float
        Scale factor (> 0) [-].
    A, C, H : array_like
        The matrices the design was made for ([1/s], [-], [-]).

    Returns
    -------
    IloLmiDesign
        The scaled design, residuals recomputed.

    Raises
    ------
    ValueError
        ``factor <= 0``.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.design.lmi import design_ilo_gains, rescale_design
    >>> A, C, H = np.array([[0.0, 1.0], [0.0, 0.0]]), np.eye(2), np.array([[0.0], [1.0]])
    >>> d = design_ilo_gains(A, C, H)
    >>> d2 = rescale_design(d, 10.0, A, C, H)
    >>> bool(np.allclose(d2.L2, 10.0 * d.L2) and np.allclose(d2.L1, d.L1))
    True
    """
    if not factor > 0:
        raise ValueError(f"factor must be > 0, got {factor}")
    P, Y, L2 = factor * design.P, factor * design.Y, factor * design.L2
    res = ilo_lmi_residuals(A, C, H, P, Y, L2, design.lam, design.disk_center, design.disk_radius)
    return replace(design, P=P, Y=Y, L2=L2, L1=np.linalg.solve(P, Y), residuals=res)
