"""Low-level fault recovery (LLFR): weighted least-effort control allocation on a chain of relative
outputs (Azizi & Khorasani 2009, eqs. (1)-(3), (6); Lemma 1; Theorem 2).

N satellites, outputs on the chain pairs (1,2), (2,3), ..., (N-1,N). With estimated actuator gains
``b_hat`` the relative constraints (2) read ``J u = p`` with the (N-1) x N matrix

    J[k, k] = -b_hat_k,  J[k, k+1] = b_hat_{k+1}                                  # Azizi2009 eq. (2)

and the allocation minimises ``sum_i alpha_i u_i^2 / 2`` subject to (2). Its Lagrange solution is
``u = W^-1 J^T lambda`` with ``W = diag(alpha)``, i.e. the weighted least-norm solution

    u = W^-1 J^T (J W^-1 J^T)^-1 p                                              (general N)

Because every row of J annihilates ``1/b_hat`` (J (1/b_hat) = 0), the optimality condition is
``sum_i (alpha_i / b_hat_i) u_i = 0``; appending it as a last row gives the square matrix of eq. (3)

    J_aug = [[J], [alpha_1/b_hat_1, ..., alpha_N/b_hat_N]],   u = J_aug^-1 [p; 0]   # eq. (3), E004-02

Both forms are implemented and tested to agree. For the faulty satellite k (0-based) with
``b_hat_k = b_k + eps`` the closed loop sees ``D = E J_aug^-1`` (eq. (6)) with ``E[k-1, k] = -eps`` and
``E[k, k] = +eps``, so ``d_m = eps f_m / DET`` with the cofactors ``f_m`` of column k of J_aug
(free of alpha_k and b_hat_k, Lemma 1) and ``DET = q2 alpha_k + q1`` (E004-03: DET = -det J_aug for
N = 4). :func:`perturbation_coefficients` computes q1, q2, f numerically for any N and interior k;
:func:`closed_form_n4` gives the closed forms for N = 4, k = 2 (1-based; E004-03).

Units: ``b``, ``b_hat``, ``alpha`` dimensionless; ``p`` [m/s^2]; ``u`` [N per unit gain].
"""

from __future__ import annotations

from dataclasses import dataclass

import jax.numpy as jnp
import numpy as np

__all__ = [
    "validate_allocation_inputs",
    "chain_matrix",
    "augmented_matrix",
    "augmented_matrix_np",
    "allocation_matrix",
    "allocate",
    "allocate_augmented",
    "PerturbationCoefficients",
    "perturbation_coefficients",
    "closed_form_n4",
    "perturbation_matrix",
]


def validate_allocation_inputs(
    alpha, b_hat, name_alpha: str = "alpha", name_b: str = "b_hat"
) -> None:
    """Raise ``ValueError`` unless every ``alpha_i > 0`` and every ``b_hat_i > 0`` (finite).

    ``alpha_i <= 0`` makes the cost not positive definite (no unique minimiser); ``b_hat_i = 0`` is a
    dead actuator, for which J_aug (eq. (3)) is undefined (division by b_hat).

    Parameters
    ----------
    alpha : array_like, shape (N,)
        Allocation weights alpha_i of eq. (3) [-]; each finite and > 0, N >= 2.
    b_hat : array_like, shape (N,)
        Estimated actuator gains b_hat_i [-]; each finite and > 0.
    name_alpha, name_b : str, optional
        Names of the two arrays in the error messages.

    Raises
    ------
    ValueError
        Shapes differ, fewer than 2 satellites, or a weight or gain that is not finite and > 0.

    Examples
    --------
    >>> from formation_ftc.design.allocation import validate_allocation_inputs
    >>> validate_allocation_inputs([1.0, 2.0, 1.0], [1.0, 0.5, 1.0])  # valid: returns None
    >>> validate_allocation_inputs([1.0, 2.0], [1.0, 0.0])
    Traceback (most recent call last):
    ...
    ValueError: b_hat must be finite and > 0 (estimated actuator gains; 0 is a dead actuator and makes J_aug of eq. (3) undefined), got [1.0, 0.0]
    """
    a, b = np.asarray(alpha, dtype=float), np.asarray(b_hat, dtype=float)
    if a.shape != b.shape:
        raise ValueError(f"{name_alpha} has shape {a.shape} but {name_b} has shape {b.shape}")
    if a.shape[-1] < 2:
        raise ValueError(f"need at least 2 satellites on the chain, got {a.shape[-1]}")
    if not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise ValueError(
            f"{name_alpha} must be finite and > 0 (allocation weights of eq. (3)), got {a.tolist()}"
        )
    if not np.all(np.isfinite(b)) or np.any(b <= 0):
        raise ValueError(
            f"{name_b} must be finite and > 0 (estimated actuator gains; 0 is a dead actuator and makes "
            f"J_aug of eq. (3) undefined), got {b.tolist()}"
        )


def chain_matrix(b_hat):
    """(N-1) x N relative-output matrix J of eq. (2) (JAX; ``b_hat`` shape (N,)).

    Parameters
    ----------
    b_hat : array_like, shape (N,)
        Estimated actuator gains [-].

    Returns
    -------
    jax.Array, shape (N-1, N)
        ``J[k, k] = -b_hat_k``, ``J[k, k+1] = b_hat_{k+1}`` [-].

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.design.allocation import chain_matrix
    >>> np.asarray(chain_matrix([1.0, 2.0, 3.0]))
    array([[-1.,  2.,  0.],
           [ 0., -2.,  3.]])
    """
    return _chain(jnp, jnp.asarray(b_hat))


def _chain(xp, b_hat):
    """J of eq. (2) in the array module ``xp`` (jax.numpy or numpy); exact, every entry is
    ``x * 1 + y * 0``."""
    n = b_hat.shape[-1]
    return -b_hat[:-1, None] * xp.eye(n - 1, n) + b_hat[1:, None] * xp.eye(n - 1, n, 1)


def _augmented(xp, alpha, b_hat):
    """J_aug of eq. (3) in the array module ``xp``: J with the row ``alpha_i / b_hat_i`` appended."""
    alpha, b_hat = xp.asarray(alpha), xp.asarray(b_hat)
    return xp.concatenate([_chain(xp, b_hat), (alpha / b_hat)[None, :]], axis=0)


def augmented_matrix(alpha, b_hat):
    """N x N matrix J_aug of eq. (3): J with the optimality row alpha_i / b_hat_i appended (E004-02).

    Parameters
    ----------
    alpha : array_like, shape (N,)
        Allocation weights [-].
    b_hat : array_like, shape (N,)
        Estimated actuator gains [-].

    Returns
    -------
    jax.Array, shape (N, N)
        ``[[J], [alpha_1/b_hat_1, ..., alpha_N/b_hat_N]]`` [-].

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.design.allocation import augmented_matrix
    >>> np.asarray(augmented_matrix([1.0, 1.0, 4.0], [1.0, 1.0, 2.0]))
    array([[-1.,  1.,  0.],
           [ 0., -1.,  2.],
           [ 1.,  1.,  2.]])
    """
    return _augmented(jnp, alpha, b_hat)


def augmented_matrix_np(alpha, b_hat) -> np.ndarray:
    """:func:`augmented_matrix` in numpy, for the design checks (the same numbers: its entries are
    ``-b_hat_k``, ``b_hat_k`` and one division ``alpha_i / b_hat_i`` each; no JAX needed).

    Parameters
    ----------
    alpha : array_like, shape (N,)
        Allocation weights [-].
    b_hat : array_like, shape (N,)
        Estimated actuator gains [-].

    Returns
    -------
    numpy.ndarray, shape (N, N)
        J_aug [-].

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.design.allocation import augmented_matrix, augmented_matrix_np
    >>> a, b = [1.0, 2.0, 1.5, 0.5], [1.0, 0.9, 1.1, 1.2]
    >>> bool(np.array_equal(augmented_matrix_np(a, b), np.asarray(augmented_matrix(a, b))))
    True
    """
    return _augmented(np, alpha, b_hat)


def allocation_matrix(alpha, b_hat):
    """N x (N-1) matrix M with ``u = M p``: weighted least-norm solution W^-1 J^T (J W^-1 J^T)^-1.

    JAX, differentiable and vmappable; call once per (alpha, b_hat), not per step.

    Parameters
    ----------
    alpha : array_like, shape (N,)
        Allocation weights (> 0) [-].
    b_hat : array_like, shape (N,)
        Estimated actuator gains (> 0) [-].

    Returns
    -------
    jax.Array, shape (N, N-1)
        M [N per unit gain per m/s^2]: maps the relative commands p [m/s^2] to the inputs u.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.design.allocation import allocation_matrix, chain_matrix
    >>> M = allocation_matrix([1.0, 1.0, 1.0], [1.0, 1.0, 1.0])
    >>> np.round(3.0 * np.asarray(M), 12)
    array([[-2., -1.],
           [ 1., -1.],
           [ 1.,  2.]])
    >>> bool(np.allclose(chain_matrix([1.0, 1.0, 1.0]) @ M, np.eye(2)))  # J M = I: constraints (2) met
    True
    """
    alpha = jnp.asarray(alpha)
    J = chain_matrix(b_hat)
    JWi = J / alpha[None, :]  # J W^-1
    G = JWi @ J.T
    return JWi.T @ jnp.linalg.inv(G)


def allocate(alpha, b_hat, p):
    """u = M p [N/unit gain] for relative commands ``p`` [m/s^2] of shape (N-1,).

    Parameters
    ----------
    alpha : array_like, shape (N,)
        Allocation weights (> 0) [-].
    b_hat : array_like, shape (N,)
        Estimated actuator gains (> 0) [-].
    p : array_like, shape (N-1,)
        Relative commands of the chain pairs [m/s^2].

    Returns
    -------
    jax.Array, shape (N,)
        Least-effort inputs u [N per unit gain].

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.design.allocation import allocate
    >>> u = allocate([1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, 0.0])
    >>> np.round(3.0 * np.asarray(u), 12)
    array([-2.,  1.,  1.])
    """
    return allocation_matrix(alpha, b_hat) @ jnp.asarray(p)


def allocate_augmented(alpha, b_hat, p):
    """u = J_aug^-1 [p; 0] (eq. (3)) -- the paper's form; equals :func:`allocate`.

    Parameters
    ----------
    alpha : array_like, shape (N,)
        Allocation weights (> 0) [-].
    b_hat : array_like, shape (N,)
        Estimated actuator gains (> 0) [-].
    p : array_like, shape (N-1,)
        Relative commands of the chain pairs [m/s^2].

    Returns
    -------
    jax.Array, shape (N,)
        Inputs u [N per unit gain], equal to :func:`allocate`'s to rounding.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.design.allocation import allocate, allocate_augmented
    >>> args = ([1.0, 2.0, 0.5], [1.0, 0.8, 1.2], [0.3, -0.1])
    >>> bool(np.allclose(allocate_augmented(*args), allocate(*args), rtol=1e-12))
    True
    """
    p = jnp.asarray(p)
    rhs = jnp.concatenate([p, jnp.zeros((1,), dtype=p.dtype)])
    return jnp.linalg.solve(augmented_matrix(alpha, b_hat), rhs)


@dataclass(frozen=True)
class PerturbationCoefficients:
    """Coefficients of Lemma 1 / Theorem 2 for the faulty satellite ``k`` (0-based).

    ``DET = q2 alpha_k + q1`` (> 0), ``f`` the cofactor column (f_m = C_{m,k} for N = 4, E004-03),
    ``sign`` = DET / det(J_aug) (-1 for N = 4).
    """

    q1: float
    q2: float
    f: np.ndarray
    sign: float

    def det(self, alpha_k: float) -> float:
        """DET(alpha_k) = q2 alpha_k + q1 [-]."""
        return self.q2 * alpha_k + self.q1

    def d(self, eps: float, alpha_k: float) -> np.ndarray:
        """Row of D (eq. (6)): d_m = eps f_m / DET [-]."""
        return eps * self.f / self.det(alpha_k)


def _cofactor(M: np.ndarray, r: int, c: int) -> float:
    minor = np.delete(np.delete(M, r, axis=0), c, axis=1)
    return float((-1) ** (r + c) * np.linalg.det(minor))


def perturbation_coefficients(alpha, b_hat, k: int) -> PerturbationCoefficients:
    """q1, q2 and cofactors f of column k of J_aug (numeric, any N >= 3, interior 0 < k < N-1).

    det(J_aug) is affine in alpha_k (expansion along the last row), so q2 and q1 follow from two
    evaluations; the sign is chosen so that q2 > 0, giving DET = q2 alpha_k + q1 (E004-03).
    ``d_m = -eps (J_aug^-1)_{k,m} = -eps C_{m,k} / det = eps f_m / DET`` with ``f = -sign * C[:, k]``.

    Parameters
    ----------
    alpha : array_like, shape (N,)
        Allocation weights (> 0) [-].
    b_hat : array_like, shape (N,)
        Estimated actuator gains (> 0) [-].
    k : int
        Faulty satellite, 0-based, interior (``0 < k < N - 1``).

    Returns
    -------
    PerturbationCoefficients
        ``q1``, ``q2`` [-] with ``DET = q2 alpha_k + q1``, the cofactor column ``f`` (N,) [-] and ``sign``
        = DET / det(J_aug) [-].

    Raises
    ------
    ValueError
        Invalid weights or gains, or ``k`` not interior.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.design.allocation import closed_form_n4, perturbation_coefficients
    >>> alpha, b_hat = [1.0, 2.0, 1.5, 0.5], [1.0, 0.9, 1.1, 1.2]
    >>> c = perturbation_coefficients(alpha, b_hat, k=1)
    >>> round(c.q1, 6), round(c.q2, 6), c.sign
    (3.073227, 1.466667, -1.0)
    >>> ref = closed_form_n4(alpha, b_hat, b_hat2=0.9)  # E004-03 closed forms agree
    >>> bool(np.isclose(c.q1, ref["q1"]) and np.isclose(c.q2, ref["q2"]))
    True
    """
    alpha, b_hat = np.asarray(alpha, dtype=float), np.asarray(b_hat, dtype=float)
    validate_allocation_inputs(alpha, b_hat)
    n = alpha.size
    if not 0 < k < n - 1:
        raise ValueError(
            f"faulty satellite index k = {k} (0-based) must be interior: 0 < k < {n - 1}"
        )

    def det_at(alpha_k: float) -> float:  # det J_aug with alpha_k in place of alpha[k]
        a = np.where(np.arange(n) == k, alpha_k, alpha)
        return float(np.linalg.det(augmented_matrix_np(a, b_hat)))

    det0 = det_at(0.0)
    slope = det_at(1.0) - det0
    sign = -1.0 if slope < 0 else 1.0
    M = augmented_matrix_np(alpha, b_hat)
    C = np.array([_cofactor(M, m, k) for m in range(n)])
    return PerturbationCoefficients(q1=sign * det0, q2=sign * slope, f=-sign * C, sign=sign)


def closed_form_n4(alpha, b, b_hat2: float) -> dict[str, object]:
    """E004-03 closed forms for N = 4, faulty satellite 2 (1-based).

    Returns q1, q2, DET (= q2 alpha_2 + q1 = -det J_aug) and the cofactors
    C_{k2} = [-a1 b3 b4/b1, b1(a3 b4^2 + a4 b3^2)/(b3 b4), a4 b1 b3/b4, -b1 b3 b4].
    ``b`` are the (healthy) gains of satellites 1, 3, 4 (b[1] is ignored and replaced by b_hat2).

    Parameters
    ----------
    alpha : array_like, shape (4,)
        Allocation weights alpha_1..alpha_4 [-].
    b : array_like, shape (4,)
        Actuator gains b_1..b_4 [-] (``b[1]`` is ignored).
    b_hat2 : float
        Estimated gain of the faulty satellite 2 [-].

    Returns
    -------
    dict
        ``"q1"``, ``"q2"``, ``"DET"`` (floats [-]) and ``"C"`` (the four cofactors C_{k2}, ndarray [-]).

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.design.allocation import closed_form_n4
    >>> r = closed_form_n4([1.0, 1.0, 1.0, 1.0], [1.0, 1.0, 1.0, 1.0], b_hat2=0.5)
    >>> r["q1"], r["q2"], r["DET"]
    (1.5, 2.0, 3.5)
    >>> r["C"]
    array([-1.,  2.,  1., -1.])
    """
    a1, a2, a3, a4 = (float(x) for x in alpha)
    b1, _, b3, b4 = (float(x) for x in b)
    bh = float(b_hat2)
    q1 = a1 * bh * b3 * b4 / b1 + a3 * b1 * bh * b4 / b3 + a4 * b1 * bh * b3 / b4  # Azizi2009 Thm 2
    q2 = b1 * b3 * b4 / bh
    C = np.array(
        [
            -a1 * b3 * b4 / b1,
            b1 * (a3 * b4**2 + a4 * b3**2) / (b3 * b4),
            a4 * b1 * b3 / b4,
            -b1 * b3 * b4,
        ]
    )  # E004-03
    return {"q1": q1, "q2": q2, "DET": q2 * a2 + q1, "C": C}


def perturbation_matrix(alpha, b_hat, k: int, eps: float) -> np.ndarray:
    """D = E J_aug^-1 (eq. (6)) with E[k-1, k] = -eps, E[k, k] = +eps; shape (N-1, N).

    Parameters
    ----------
    alpha : array_like, shape (N,)
        Allocation weights (> 0) [-].
    b_hat : array_like, shape (N,)
        Estimated actuator gains (> 0) [-].
    k : int
        Faulty satellite, 0-based, interior.
    eps : float
        Gain estimation error eps = b_hat_k - b_k [-].

    Returns
    -------
    numpy.ndarray, shape (N-1, N)
        D [-]; rows k-1 and k are ``d`` and ``-d`` with ``d`` = :meth:`PerturbationCoefficients.d`
        (Lemma 1), the other rows zero.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.design.allocation import perturbation_coefficients, perturbation_matrix
    >>> alpha, b_hat = [1.0, 2.0, 1.5, 0.5], [1.0, 0.9, 1.1, 1.2]
    >>> D = perturbation_matrix(alpha, b_hat, k=1, eps=0.1)
    >>> D.shape
    (3, 4)
    >>> d = perturbation_coefficients(alpha, b_hat, k=1).d(0.1, alpha[1])
    >>> bool(np.allclose(D[0], d) and np.allclose(D[1], -d))
    True
    """
    alpha, b_hat = np.asarray(alpha, dtype=float), np.asarray(b_hat, dtype=float)
    n = alpha.size
    E = np.zeros((n - 1, n))
    E[k - 1, k] = -eps
    E[k, k] = eps
    return E @ np.linalg.inv(augmented_matrix_np(alpha, b_hat))
