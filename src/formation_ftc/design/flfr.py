"""Formation-level fault recovery (FLFR): analytic choice of the allocation weight alpha_k of a
partially recovered satellite (Azizi & Khorasani 2009, eqs. (7)-(11), Theorems 1-2).

Reduced error model (7) with X = [e_{k-1,k}, e'_{k-1,k}, e_{k,k+1}, e'_{k,k+1}] (E004-01)::

    X' = (I + Delta) A X + [0, 1, 0, -1]^T (d . xdd_des)                         # eq. (7)
    A = blkdiag([[0, 1], [-lambda0, -lambda1]] x 2),  Delta rows 2 / 4 = +/-[0, d1, 0, d2]

with d_m = eps f_m / DET (see :mod:`formation_ftc.design.allocation`). Theorem 2 bound::

    |X_i(t)| <= |eps| H_i / (q2 alpha_k + q1),
    H_i = sup_t |(G_i4 - G_i2) * (f . xdd_des)|,  G(s) = (sI - A_clp)^-1           # eq. (8)

H_i is computed by *simulating* ``X' = A_clp X + [0, 1, 0, -1]^T w(t)``,
``w = f . xdd_des``, from zero initial conditions (RK4, lax.scan) and taking sup_t |X_i|, with A_clp at
a reference alpha_k (default 1) and eps = +/- B_eps (the larger H is kept, so (9)/(11) stay
conservative for alpha_k above the reference). The nominal-A variant (Delta = 0) is reported too.

Design equations::

    alpha_k = B_eps H / (q2 e_s) - q1 / q2                                          # eq. (9)
    alpha_k = B_eps (1 - pi) H / (q2 e_s) - q1 / q2   (eps uniform on [-B_eps, B_eps]) # eq. (11)

pi is the allowed violation probability; pi = 0 is the deterministic case (9), so 0 <= pi < 1 is
accepted. External disturbance floor: ``T_i = sup_omega |G_i4(j omega) - G_i2(j omega)| B_ext``
(E004-07: over all omega); no alpha can bring the error below T_i, so an ``e_s <= T_i`` is reported as
infeasible. T_i uses the certified H-infinity norm of :func:`formation_ftc.design.small_gain.hinf_norm` (an
upper bound, so the floor is never underestimated). Units: e_s, H_i/|DET| and T_i in m; B_eps
dimensionless; w in m/s^2.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass, field

import jax
import jax.numpy as jnp
import numpy as np
import scipy.linalg

from formation_ftc.core.integrators import rk4_step
from formation_ftc.design.allocation import PerturbationCoefficients, perturbation_coefficients
from formation_ftc.design.small_gain import SmallGainResult, hinf_norm, small_gain_margin

__all__ = [
    "InfeasibleSpecification",
    "INPUT_DIRECTION",
    "error_dynamics_matrix",
    "reduced_model",
    "simulate_reduced_model",
    "convolution_supremum",
    "disturbance_floor",
    "validate_violation_probability",
    "alpha_deterministic",
    "alpha_probabilistic",
    "FlfrDesign",
    "design_flfr",
]

#: Input direction of the perturbation w in X' = A_clp X + b w (eq. (7), D-bar)
INPUT_DIRECTION = np.array([0.0, 1.0, 0.0, -1.0])


class InfeasibleSpecification(ValueError):
    """The mission bound e_s is at or below the disturbance floor T_i: no alpha_k can meet it."""


def error_dynamics_matrix(lam0: float, lam1: float) -> np.ndarray:
    """A of eq. (7): blkdiag([[0, 1], [-lambda0, -lambda1]] x 2) [1/s, 1/s^2].

    Parameters
    ----------
    lam0 : float
        lambda0 of the error dynamics s^2 + lambda1 s + lambda0 (> 0) [1/s^2].
    lam1 : float
        lambda1 (> 0) [1/s].

    Returns
    -------
    numpy.ndarray, shape (4, 4)
        A [1/s, 1/s^2].

    Raises
    ------
    ValueError
        ``lam0 <= 0`` or ``lam1 <= 0``.

    Examples
    --------
    >>> from formation_ftc.design.flfr import error_dynamics_matrix
    >>> error_dynamics_matrix(2.0, 3.0)
    array([[ 0.,  1.,  0.,  0.],
           [-2., -3.,  0.,  0.],
           [ 0.,  0.,  0.,  1.],
           [ 0.,  0., -2., -3.]])
    """
    if lam0 <= 0 or lam1 <= 0:
        raise ValueError(
            f"lambda0 and lambda1 must be > 0 (Hurwitz s^2 + l1 s + l0), got {lam0}, {lam1}"
        )
    blk = np.array([[0.0, 1.0], [-lam0, -lam1]])
    return scipy.linalg.block_diag(blk, blk)


def reduced_model(
    lam0: float, lam1: float, d12: tuple[float, float]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A, Delta, A_clp = (I + Delta) A) of eq. (7) for the first two D entries (d1, d2).

    Parameters
    ----------
    lam0 : float
        lambda0 (> 0) [1/s^2].
    lam1 : float
        lambda1 (> 0) [1/s].
    d12 : tuple of float
        The first two entries (d1, d2) of the D row of the faulty satellite [-].

    Returns
    -------
    A : numpy.ndarray, shape (4, 4)
        Nominal error dynamics [1/s, 1/s^2].
    Delta : numpy.ndarray, shape (4, 4)
        Perturbation [-]: rows 2 and 4 are ``+/-[0, d1, 0, d2]``.
    A_clp : numpy.ndarray, shape (4, 4)
        ``(I + Delta) A`` [1/s, 1/s^2].

    Examples
    --------
    >>> from formation_ftc.design.flfr import reduced_model
    >>> A, Delta, A_clp = reduced_model(2.0, 3.0, (0.1, 0.0))
    >>> A_clp[1]
    array([-2.2, -3.3,  0. ,  0. ])
    >>> A_clp[3]
    array([ 0.2,  0.3, -2. , -3. ])
    """
    A = error_dynamics_matrix(lam0, lam1)
    d1, d2 = (float(x) for x in d12)
    Delta = np.zeros((4, 4))
    Delta[1, 1], Delta[1, 3] = d1, d2
    Delta[3, 1], Delta[3, 3] = -d1, -d2
    return A, Delta, (np.eye(4) + Delta) @ A


@functools.cache
def _simulate_jit() -> Callable:
    """:func:`_simulate` jitted, made on first use (not at import: ``check`` imports this module
    without JAX, :mod:`formation_ftc._lazy_jax`)."""
    return jax.jit(_simulate, static_argnames=("w_fn", "n_steps", "record_every"))


def _simulate(A_clp, b_vec, weights, w_fn, dt, n_steps: int, record_every: int):
    def rhs(t, x):
        return A_clp @ x + b_vec * jnp.dot(weights, jnp.atleast_1d(w_fn(t)))

    def inner(carry, _):
        k, x, peak = carry
        x = rk4_step(rhs, k * dt, x, dt)
        return (k + 1, x, jnp.maximum(peak, jnp.abs(x))), None

    def outer(carry, _):
        carry, _ = jax.lax.scan(inner, carry, None, length=record_every)
        return carry, carry[1]

    x0 = jnp.zeros(A_clp.shape[0])
    carry0 = (jnp.asarray(0, jnp.int64), x0, jnp.abs(x0))
    (_, _, peak), xs = jax.lax.scan(outer, carry0, None, length=n_steps // record_every)
    return jnp.concatenate([x0[None], xs], axis=0), peak


def simulate_reduced_model(
    A_clp,
    w_fn: Callable,
    horizon: float,
    dt: float,
    weights=(1.0,),
    record_every: int = 1,
    b_vec=INPUT_DIRECTION,
) -> tuple[np.ndarray, np.ndarray]:
    """Integrate ``X' = A_clp X + b_vec (weights . w(t))`` from X(0) = 0 with RK4 (w at the stages).

    ``w_fn(t)`` is a JAX-traceable function returning a scalar or a vector matching ``weights``; it is a
    static jit argument, so pass the same function object to reuse the compilation.
    Returns (records of shape (n_steps/record_every + 1, 4), per-state sup_t |X_i| over every step).

    Parameters
    ----------
    A_clp : array_like, shape (4, 4)
        Closed-loop matrix [1/s, 1/s^2].
    w_fn : callable
        ``w(t)`` [m/s^2], t [s]; JAX-traceable.
    horizon : float
        Simulated time [s]; a multiple of ``dt``.
    dt : float
        RK4 step [s].
    weights : array_like, optional
        Weights of the components of ``w`` [-].
    record_every : int, optional
        Steps between records (a divisor of ``horizon / dt``).
    b_vec : array_like, shape (4,), optional
        Input direction [-] (default :data:`INPUT_DIRECTION`).

    Returns
    -------
    records : numpy.ndarray, shape (horizon / dt / record_every + 1, 4)
        X at the recorded times [m, m/s].
    peak : numpy.ndarray, shape (4,)
        sup_t |X_i| over every step [m, m/s].

    Raises
    ------
    ValueError
        ``dt`` does not divide ``horizon`` or ``record_every`` does not divide the step count.

    Examples
    --------
    Unit step of w on the nominal model (DC gain of the position errors 1 / lambda0 = 0.5 m):

    >>> import numpy as np
    >>> from formation_ftc.design.flfr import error_dynamics_matrix, simulate_reduced_model
    >>> A = error_dynamics_matrix(2.0, 3.0)
    >>> xs, peak = simulate_reduced_model(A, lambda t: 1.0 + 0.0 * t, horizon=10.0, dt=0.01, record_every=500)
    >>> xs.shape
    (3, 4)
    >>> np.round(xs[-1, [0, 2]], 4)  # position errors at t = 10 s [m]
    array([ 0.5, -0.5])
    >>> np.round(peak, 4)
    array([0.5 , 0.25, 0.5 , 0.25])
    """
    n_steps = round(horizon / dt)
    if n_steps < 1 or abs(n_steps * dt - horizon) > 1e-9 * max(horizon, 1.0):
        raise ValueError(f"dt = {dt} s must divide horizon = {horizon} s")
    if n_steps % record_every:
        raise ValueError(f"record_every = {record_every} must divide horizon/dt = {n_steps}")
    A, b, w, h = (jnp.asarray(x, dtype=jnp.float64) for x in (A_clp, b_vec, weights, dt))
    xs, peak = _simulate_jit()(A, b, w, w_fn, h, n_steps, record_every)
    return np.asarray(xs), np.asarray(peak)


def convolution_supremum(
    A_clp, w_fn: Callable, horizon: float, dt: float, weights=(1.0,)
) -> np.ndarray:
    """H_i = sup_{0<=t<=horizon} |(G_i4 - G_i2) * (weights . w)| for i = 1..4 (eq. (8)), by simulation.

    The sign convention of the input direction does not matter (absolute value). Remembered for the
    last few distinct inputs (the matrix's and weights' exact values, ``w_fn`` by identity, horizon,
    step): designs for several violation probabilities or mission bounds of one formation simulate the
    same closed loops, each about 0.6 s at the paper's 300 s and 1 ms.

    Parameters
    ----------
    A_clp : array_like, shape (4, 4)
        Closed-loop matrix [1/s, 1/s^2].
    w_fn : callable
        ``w(t)`` [m/s^2], t [s]; JAX-traceable.
    horizon : float
        Time over which the supremum is taken [s].
    dt : float
        RK4 step [s].
    weights : array_like, optional
        Weights of the components of ``w`` (the cofactors f) [-].

    Returns
    -------
    numpy.ndarray, shape (4,)
        H_i [m, m/s] (per unit |eps| / DET).

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.design.flfr import convolution_supremum, error_dynamics_matrix
    >>> A = error_dynamics_matrix(2.0, 3.0)
    >>> np.round(convolution_supremum(A, lambda t: 1.0 + 0.0 * t, horizon=10.0, dt=0.01, weights=(2.0,)), 4)
    array([0.9999, 0.5   , 0.9999, 0.5   ])
    """
    A = np.ascontiguousarray(A_clp, dtype=np.float64)
    w = np.ascontiguousarray(weights, dtype=np.float64)
    return _supremum(
        (A.tobytes(), A.shape), w_fn, float(horizon), float(dt), (w.tobytes(), w.shape)
    ).copy()


@functools.lru_cache(maxsize=16)
def _supremum(a_key: tuple, w_fn: Callable, horizon: float, dt: float, w_key: tuple) -> np.ndarray:
    """:func:`convolution_supremum` cached; ``a_key`` / ``w_key``: (bytes, shape) of A_clp / weights."""
    A = np.frombuffer(a_key[0], dtype=np.float64).reshape(a_key[1])
    weights = np.frombuffer(w_key[0], dtype=np.float64).reshape(w_key[1])
    # the peak is taken at every step inside the loop; no record is needed between the two ends (one
    # loop of n steps instead of n loops of one step with a record each: 0.21 -> 0.08 s at 300 s / 1 ms,
    # the same peak bit for bit)
    every = max(1, round(horizon / dt))
    _, peak = simulate_reduced_model(A, w_fn, horizon, dt, weights, record_every=every)
    return peak


def disturbance_floor(A_clp, b_ext: float) -> np.ndarray:
    """T_i = sup_omega |G_i4(j omega) - G_i2(j omega)| B_ext [m] for i = 1..4 (E004-07: all omega).

    The supremum is the certified H-infinity norm (upper bound, see :func:`hinf_norm`); an A_clp that is
    not Hurwitz gives T_i = inf (no finite floor, so every e_s is infeasible).

    Parameters
    ----------
    A_clp : array_like, shape (4, 4)
        Closed-loop matrix [1/s, 1/s^2].
    b_ext : float
        Bound on the external disturbance acceleration (>= 0) [m/s^2].

    Returns
    -------
    numpy.ndarray, shape (4,)
        T_i [m for the position errors, m/s for their rates].

    Raises
    ------
    ValueError
        ``b_ext < 0``.

    Examples
    --------
    For ``1 / (s^2 + 3 s + 2)`` the peak gain is the DC gain 0.5, for ``s / (s^2 + 3 s + 2)`` it is 1/3:

    >>> import numpy as np
    >>> from formation_ftc.design.flfr import disturbance_floor, error_dynamics_matrix
    >>> np.round(disturbance_floor(error_dynamics_matrix(2.0, 3.0), b_ext=0.01), 6)
    array([0.005   , 0.003333, 0.005   , 0.003333])
    """
    if b_ext < 0:
        raise ValueError(f"b_ext (disturbance bound) must be >= 0 m/s^2, got {b_ext}")
    if not b_ext > 0:
        return np.zeros(4)
    rows = np.eye(4)  # C = rows[i : i + 1]: the output X_i
    B = INPUT_DIRECTION[:, None]
    return np.array([hinf_norm(A_clp, B, rows[i : i + 1]).value * b_ext for i in range(4)])


def validate_violation_probability(pi: float) -> float:
    """Accept 0 <= pi < 1 (pi = 0 is the deterministic design (9)); raise ValueError otherwise.

    Parameters
    ----------
    pi : float
        Allowed violation probability [-].

    Returns
    -------
    float
        ``pi`` as a float [-].

    Raises
    ------
    ValueError
        ``pi`` outside [0, 1) or not finite.

    Examples
    --------
    >>> from formation_ftc.design.flfr import validate_violation_probability
    >>> validate_violation_probability(0.05)
    0.05
    >>> validate_violation_probability(1.0)
    Traceback (most recent call last):
    ...
    ValueError: violation probability pi must satisfy 0 <= pi < 1 (pi = 0 is the deterministic design of eq. (9)), got 1.0
    """
    p = float(pi)
    if not np.isfinite(p) or p < 0.0 or p >= 1.0:
        raise ValueError(
            f"violation probability pi must satisfy 0 <= pi < 1 (pi = 0 is the deterministic design "
            f"of eq. (9)), got {pi}"
        )
    return p


def alpha_probabilistic(
    b_eps: float, H: float, q1: float, q2: float, e_s: float, pi: float = 0.0, floor: float = 0.0
) -> float:
    """alpha_k of eq. (11) (eq. (9) for pi = 0) with the mission bound reduced by ``floor`` [m].

    Raises :class:`InfeasibleSpecification` if ``e_s <= floor`` and ValueError on bad input.

    Parameters
    ----------
    b_eps : float
        Bound B_eps on the gain estimation error (> 0) [-].
    H : float
        Convolution supremum H of eq. (8) [m].
    q1, q2 : float
        Coefficients of DET = q2 alpha_k + q1 (q2 > 0) [-].
    e_s : float
        Mission bound on the relative position error (> 0) [m].
    pi : float, optional
        Allowed violation probability, 0 <= pi < 1 [-].
    floor : float, optional
        Disturbance floor T subtracted from ``e_s`` [m].

    Returns
    -------
    float
        alpha_k [-].

    Raises
    ------
    InfeasibleSpecification
        ``e_s <= floor``.
    ValueError
        Bad input.

    Examples
    --------
    >>> from formation_ftc.design.flfr import alpha_probabilistic
    >>> round(alpha_probabilistic(b_eps=0.5, H=1.0, q1=1.0, q2=2.0, e_s=0.1), 6)
    2.0
    >>> round(alpha_probabilistic(b_eps=0.5, H=1.0, q1=1.0, q2=2.0, e_s=0.1, pi=0.2), 6)
    1.5
    """
    pi = validate_violation_probability(pi)
    if not b_eps > 0:
        raise ValueError(f"B_eps (bound on the estimation error) must be > 0, got {b_eps}")
    if not e_s > 0:
        raise ValueError(f"e_s (mission error bound) must be > 0 m, got {e_s}")
    if q2 <= 0:
        raise ValueError(f"q2 must be > 0, got {q2}")
    if e_s <= floor:
        raise InfeasibleSpecification(
            f"infeasible: e_s = {e_s:.6g} m is not above the disturbance floor T = {floor:.6g} m; "
            f"no alpha can meet it (Azizi2009 Sec. IV)"
        )
    return b_eps * (1.0 - pi) * H / (q2 * (e_s - floor)) - q1 / q2  # Azizi2009 eq. (11)


def alpha_deterministic(
    b_eps: float, H: float, q1: float, q2: float, e_s: float, floor: float = 0.0
) -> float:
    """alpha_k of eq. (9) (conservative, worst-case eps).

    Parameters
    ----------
    b_eps : float
        Bound B_eps on the gain estimation error (> 0) [-].
    H : float
        Convolution supremum H of eq. (8) [m].
    q1, q2 : float
        Coefficients of DET = q2 alpha_k + q1 (q2 > 0) [-].
    e_s : float
        Mission bound (> 0) [m].
    floor : float, optional
        Disturbance floor T subtracted from ``e_s`` [m].

    Returns
    -------
    float
        alpha_k [-] (:func:`alpha_probabilistic` with pi = 0).

    Raises
    ------
    InfeasibleSpecification
        ``e_s <= floor``.

    Examples
    --------
    >>> from formation_ftc.design.flfr import alpha_deterministic
    >>> round(alpha_deterministic(b_eps=0.5, H=1.0, q1=1.0, q2=2.0, e_s=0.1), 6)
    2.0
    """
    return alpha_probabilistic(b_eps, H, q1, q2, e_s, 0.0, floor)  # Azizi2009 eq. (9)


@dataclass(frozen=True)
class FlfrDesign:
    """Result of :func:`design_flfr`.

    verdict: "feasible" (alpha from (11) above the current weight), "llfr-sufficient" (the bound already
    holds at the current weight) or "infeasible" (e_s <= floor). ``alpha`` maps pi -> alpha_k
    (None when infeasible); ``alpha_nominal_H`` the same with H from the nominal A.
    """

    verdict: str
    message: str
    coefficients: PerturbationCoefficients
    H: float
    H_nominal: float
    H_eps_sign: float
    floor: float
    alpha: dict[float, float | None]
    alpha_nominal_H: dict[float, float | None]
    bound_at_reference: float
    delta_norm_reference: float
    small_gain: SmallGainResult
    eig_clp: np.ndarray = field(repr=False)


def design_flfr(
    alpha,
    b_hat,
    k: int,
    b_eps: float,
    lam0: float,
    lam1: float,
    e_s: float,
    pis,
    w_fn: Callable,
    horizon: float,
    dt: float,
    b_ext: float = 0.0,
    alpha_ref: float = 1.0,
    subtract_floor: bool = False,
) -> FlfrDesign:
    """FLFR design for faulty satellite ``k`` (0-based, interior) with current weights ``alpha``.

    ``w_fn(t)`` [m/s^2] must be the *unscaled* desired relative acceleration row ``xdd_des`` (shape
    (N-1,)) as a JAX function; it is combined with the cofactors f inside. H uses A_clp at
    ``alpha_k = alpha_ref`` and eps = +/- b_eps (larger kept). ``subtract_floor`` uses e_s - T in (11).

    Parameters
    ----------
    alpha : array_like, shape (4,)
        Current allocation weights [-].
    b_hat : array_like, shape (4,)
        Estimated actuator gains [-].
    k : int
        Faulty satellite, 0-based (the reduced model (7) is implemented for k = 1).
    b_eps : float
        Bound B_eps on the gain estimation error (> 0) [-].
    lam0 : float
        lambda0 (> 0) [1/s^2].
    lam1 : float
        lambda1 (> 0) [1/s].
    e_s : float
        Mission bound on the relative position error (> 0) [m].
    pis : iterable of float
        Violation probabilities to design for, each 0 <= pi < 1 [-].
    w_fn : callable
        ``xdd_des(t)`` [m/s^2], shape (N-1,), t [s]; JAX-traceable.
    horizon : float
        Time over which H is taken [s].
    dt : float
        RK4 step [s].
    b_ext : float, optional
        External disturbance bound [m/s^2] (0: no floor).
    alpha_ref : float, optional
        Reference alpha_k of A_clp [-].
    subtract_floor : bool, optional
        Use ``e_s - T`` in (11).

    Returns
    -------
    FlfrDesign
        Verdict, message, H, floor and alpha_k per pi (see :class:`FlfrDesign`).

    Raises
    ------
    ValueError
        N != 4 or k != 1, or invalid inputs.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from formation_ftc.design.flfr import design_flfr
    >>> d = design_flfr([1.0, 1.0, 1.0, 1.0], [1.0, 1.0, 1.0, 1.0], k=1, b_eps=0.5, lam0=2.0, lam1=3.0,
    ...                 e_s=0.01, pis=[0.0, 0.5], horizon=5.0, dt=0.01,
    ...                 w_fn=lambda t: jnp.array([jnp.sin(t), 0.0, jnp.cos(t)]))
    >>> d.verdict
    'feasible'
    >>> {pi: round(a, 3) for pi, a in d.alpha.items()}
    {0.0: 35.644, 0.5: 16.322}
    """
    alpha = np.asarray(alpha, dtype=float)
    coeff = perturbation_coefficients(alpha, b_hat, k)
    f = coeff.f[: len(coeff.f) - 1]  # f_N multiplies the 0 entry of [p; 0]
    if alpha.size != 4 or k != 1:
        raise ValueError(
            "the reduced model (7) is implemented for N = 4 and faulty satellite 2 (k = 1)"
        )

    A = error_dynamics_matrix(lam0, lam1)
    H_nom = float(np.max(convolution_supremum(A, w_fn, horizon, dt, f)[[0, 2]]))
    best, best_sign, best_clp = -1.0, 1.0, A
    for sgn in (+1.0, -1.0):
        d = coeff.d(sgn * b_eps, alpha_ref)
        _, _, A_clp = reduced_model(lam0, lam1, (d[0], d[1]))
        h = float(np.max(convolution_supremum(A_clp, w_fn, horizon, dt, f)[[0, 2]]))
        if h > best:
            best, best_sign, best_clp = h, sgn, A_clp
    d_ref = coeff.d(b_eps, alpha_ref)
    _, Delta_ref, _ = reduced_model(lam0, lam1, (d_ref[0], d_ref[1]))
    floor = float(np.max(disturbance_floor(best_clp, b_ext)[[0, 2]])) if b_ext > 0 else 0.0
    bound_ref = b_eps * best / coeff.det(alpha_ref)
    pis = [validate_violation_probability(p) for p in pis]
    fl = floor if subtract_floor else 0.0

    def alphas(H: float) -> dict[float, float | None]:
        """pi -> alpha_k of (11) for the supremum H (None when e_s is at or below the floor)."""
        if e_s <= floor:
            return dict.fromkeys(pis)
        return {p: alpha_probabilistic(b_eps, H, coeff.q1, coeff.q2, e_s, p, fl) for p in pis}

    bound_text = f"bound (8) at alpha_{k + 1} = {alpha_ref} is {bound_ref:.4g} m"
    if e_s <= floor:
        verdict = "infeasible"
        msg = (
            f"infeasible: e_s = {e_s:.6g} m is not above the disturbance floor T = {floor:.6g} m "
            f"(sup_omega |G_14 - G_12| B_ext with B_ext = {b_ext:.3g} m/s^2); no alpha_{k + 1} can meet it"
        )
    elif bound_ref <= e_s:
        verdict = "llfr-sufficient"
        msg = f"{bound_text} <= e_s = {e_s} m: FLFR not needed"
    else:
        verdict = "feasible"
        msg = f"{bound_text} > e_s = {e_s} m; FLFR raises alpha_{k + 1} from {float(alpha[k]):g}"
    return FlfrDesign(
        verdict=verdict,
        message=msg,
        coefficients=coeff,
        H=best,
        H_nominal=H_nom,
        H_eps_sign=best_sign,
        floor=floor,
        alpha=alphas(best),
        alpha_nominal_H=alphas(H_nom),
        bound_at_reference=bound_ref,
        delta_norm_reference=float(np.linalg.norm(Delta_ref, 2)),
        small_gain=small_gain_margin(A),
        eig_clp=np.linalg.eigvals(best_clp),
    )
