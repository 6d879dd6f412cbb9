"""Condition calculators of the state-varying switched-system theorems (Yang2013 Sec. 3).

Pure numpy, evaluated offline (never inside the time loop). Symbols of the paper:

* ``D = |[d_bar, iota_bar]|`` -- disturbance bound (Definition 1)
* ``S = max |S_ij|`` -- largest variation-matrix norm. The paper's value sqrt(5) is the *Frobenius*
  norm; the proof step |S X| <= S |X| needs the *induced 2-norm*; both are provided (E001-04)
* ``eta`` -- Lyapunov decay rate (18), ``zeta = max_j sqrt(n_j eps)`` (20)
* dwell-time bound (21), new-state bound (22), initial-state bound (24), guaranteed envelope
  ``eps + (S+2) zeta D`` and pre-switch bound ``eps1 + zeta D`` (proof of Theorem 1), and the
  fault-tolerance condition (29) of Theorem 2.

Each checker returns an :class:`Inequality` naming the equation, its two sides and whether it holds,
so that callers can report *which* inequality a scenario violates.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = [
    "Inequality",
    "variation_norm",
    "max_variation_norm",
    "disturbance_bound",
    "zeta_from_epsilon",
    "lyapunov_epsilon",
    "eta_from_gains",
    "translational_decay_rate",
    "gains_for_decay_rate",
    "dwell_time_bound",
    "new_state_bound",
    "initial_state_bound",
    "state_envelope",
    "pre_switch_bound",
    "condition_29_margin",
    "check_epsilons",
    "check_dwell_time",
    "check_new_state",
    "check_initial_state",
    "check_condition_29",
]


@dataclass(frozen=True)
class Inequality:
    """``lhs relation rhs`` with the paper's equation number; ``holds`` is its truth value."""

    name: str
    reference: str
    lhs: float
    relation: str  # one of "<=", ">=", "<", ">"
    rhs: float
    holds: bool
    detail: str = ""

    def __str__(self) -> str:
        state = "holds" if self.holds else "VIOLATED"
        return (
            f"{self.reference} {self.name}: {self.lhs:.6g} {self.relation} {self.rhs:.6g} ({state})"
        )


#: relation -> its test of ``lhs`` against ``rhs`` (the non-strict ones to a tolerance of 1e-12)
_RELATIONS = {
    "<=": lambda lhs, rhs: lhs <= rhs + 1e-12,
    ">=": lambda lhs, rhs: lhs >= rhs - 1e-12,
    "<": lambda lhs, rhs: lhs < rhs,
    ">": lambda lhs, rhs: lhs > rhs,
}


def _inequality(
    name: str, reference: str, lhs: float, relation: str, rhs: float, detail: str = ""
) -> Inequality:
    """The :class:`Inequality` ``lhs relation rhs`` with its truth value."""
    holds = _RELATIONS[relation](lhs, rhs)
    return Inequality(name, reference, lhs, relation, rhs, holds, detail=detail)


def variation_norm(S: np.ndarray, kind: str = "frobenius") -> float:
    """Norm of one variation matrix S_ij (n_j x n_i): ``"frobenius"`` (paper) or ``"induced2"`` (E001-04).

    Parameters
    ----------
    S : array_like, shape (n_j, n_i)
        Variation matrix S_ij [-] (a 1-d or scalar input is read as one row).
    kind : {"frobenius", "induced2"}, optional
        Frobenius norm (the paper's value) or induced 2-norm (what the proof needs).

    Returns
    -------
    float
        The norm [-].

    Raises
    ------
    ValueError
        Unknown ``kind``.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.design.dwell_time import variation_norm
    >>> S = np.array([[1.0, 0.0], [0.0, 2.0]])
    >>> round(variation_norm(S), 6), variation_norm(S, "induced2")
    (2.236068, 2.0)
    """
    S = np.atleast_2d(np.asarray(S, dtype=float))
    if kind not in ("frobenius", "induced2"):
        raise ValueError(f"variation norm kind must be 'frobenius' or 'induced2', got {kind!r}")
    return float(np.linalg.norm(S, "fro" if kind == "frobenius" else 2))


def max_variation_norm(matrices: Sequence[np.ndarray], kind: str = "frobenius") -> float:
    """``S = max_ij |S_ij|`` over the given variation matrices (Yang2013, after (20)).

    Parameters
    ----------
    matrices : sequence of array_like
        The variation matrices S_ij [-] (at least one).
    kind : {"frobenius", "induced2"}, optional
        Norm of each matrix, see :func:`variation_norm`.

    Returns
    -------
    float
        S [-].

    Raises
    ------
    ValueError
        No matrix given, or unknown ``kind``.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.design.dwell_time import max_variation_norm
    >>> max_variation_norm([np.eye(2), 3.0 * np.eye(1)])
    3.0
    """
    if not matrices:
        raise ValueError("at least one variation matrix is needed to compute S")
    return max(variation_norm(S, kind) for S in matrices)


def disturbance_bound(d_bar: float, iota_bar: float) -> float:
    """``D = |[d_bar, iota_bar]|`` (Definition 1); d_bar [N], iota_bar [N m] (mixed units as in the paper).

    Parameters
    ----------
    d_bar : float
        Bound on the disturbance force [N].
    iota_bar : float
        Bound on the disturbance torque [N m].

    Returns
    -------
    float
        D = sqrt(d_bar^2 + iota_bar^2) (mixed units [N, N m], as in the paper).

    Examples
    --------
    >>> from formation_ftc.design.dwell_time import disturbance_bound
    >>> disturbance_bound(3.0, 4.0)
    5.0
    """
    return float(np.hypot(d_bar, iota_bar))


def lyapunov_epsilon(nu1: float, nu2: float, masses: Sequence[float]) -> float:
    """``eps = max_i [1/(nu1 M_i^2), 1/nu2]`` of (18).

    Parameters
    ----------
    nu1, nu2 : float
        Positive constants nu_1, nu_2 of the Lyapunov function (18) [-].
    masses : sequence of float
        Spacecraft masses M_i [kg].

    Returns
    -------
    float
        eps of (18) [-].

    Examples
    --------
    >>> from formation_ftc.design.dwell_time import lyapunov_epsilon
    >>> lyapunov_epsilon(0.5, 0.25, [1.0, 2.0])
    4.0
    """
    return float(max(max(1.0 / (nu1 * m**2) for m in masses), 1.0 / nu2))


def zeta_from_epsilon(mode_sizes: Sequence[int], eps_lyap: float) -> float:
    """``zeta = max_j sqrt(n_j eps)`` (after (20)).

    Parameters
    ----------
    mode_sizes : sequence of int
        State dimensions n_j of the switching modes [-].
    eps_lyap : float
        eps of (18), e.g. from :func:`lyapunov_epsilon` [-].

    Returns
    -------
    float
        zeta [-].

    Examples
    --------
    >>> from formation_ftc.design.dwell_time import zeta_from_epsilon
    >>> zeta_from_epsilon([12, 16], 0.25)
    2.0
    """
    return float(np.sqrt(max(mode_sizes) * eps_lyap))


def eta_from_gains(
    K1: float, K2: float, K3: float, K4: float, K5: float, nu1: float, nu2: float, nu3: float
) -> float:
    """Printed decay rate of (18): ``eta = 2 min[K1, K2 - nu1, K3 - nu2 - nu3, K4 - 1/nu3, K5]``.

    E001-03: (14) cannot be derived from (12)-(13), so this number is the paper's claim, not a proven
    rate. :func:`translational_decay_rate` gives the exact rate of the closed loop.

    Parameters
    ----------
    K1, K2, K3, K4, K5 : float
        Control gains of Yang2013 (12)-(13) [-].
    nu1, nu2, nu3 : float
        Lyapunov constants of (18) [-].

    Returns
    -------
    float
        The printed eta [1/s].

    Examples
    --------
    >>> from formation_ftc.design.dwell_time import eta_from_gains
    >>> eta_from_gains(1.0, 2.0, 3.0, 4.0, 5.0, nu1=0.5, nu2=0.5, nu3=1.0)
    2.0
    """
    return 2.0 * min(K1, K2 - nu1, K3 - nu2 - nu3, K4 - 1.0 / nu3, K5)


def translational_decay_rate(K1: float, K2: float) -> float:
    """Exact decay rate of ``e_ddot + K2 e_dot + (K1 + 1) e = 0`` (closed loop of (12)): ``-max Re(lambda)``.

    Amplitudes decay as ``exp(-rate t)``; for the scenario gains (E001-10) rate = K2/2 = eta/2 (underdamped). A
    negative value is a growth rate (faulty gain K2f < 0: rate = K2f/2 = -eta1/2).

    Parameters
    ----------
    K1 : float
        Position gain [-] (the loop's stiffness is K1 + 1).
    K2 : float
        Damping gain [1/s].

    Returns
    -------
    float
        The decay rate ``-max Re(lambda)`` [1/s] (negative: growth rate).

    Examples
    --------
    >>> from formation_ftc.design.dwell_time import translational_decay_rate
    >>> round(translational_decay_rate(0.5, 1.0), 12)  # underdamped: K2 / 2
    0.5
    >>> round(translational_decay_rate(0.5, -1.0), 12)  # a faulty negative gain grows
    -0.5
    """
    lam = np.roots([1.0, K2, K1 + 1.0])
    return float(-np.max(lam.real))


def gains_for_decay_rate(eta: float, K1: float | None = None) -> tuple[float, float]:
    """(K1, K2) realising amplitude decay ``exp(-eta t / 2)`` of the translational loop.

    The closed loop of (12) is ``e_ddot + K2 e_dot + (K1+1) e = 0``; when underdamped
    (K2^2 < 4 (K1+1)) its eigenvalues have real part -K2/2, so ``K2 = eta`` gives |x| ~ exp(-eta t/2),
    matching W ~ exp(-eta t) of (20). K1 > 0 (E001-01) is free; the scenarios choose ``K1 = eta/2`` (E001-10).

    Parameters
    ----------
    eta : float
        Wanted decay rate of W (> 0) [1/s]; amplitudes decay as exp(-eta t / 2).
    K1 : float, optional
        Position gain [-]; default ``eta / 2`` (E001-10).

    Returns
    -------
    tuple of float
        ``(K1, K2)`` with ``K2 = eta`` [-, 1/s].

    Raises
    ------
    ValueError
        ``eta <= 0``, or the loop would not be underdamped for this K1.

    Examples
    --------
    >>> from formation_ftc.design.dwell_time import gains_for_decay_rate, translational_decay_rate
    >>> K1, K2 = gains_for_decay_rate(0.4)
    >>> K1, K2
    (0.2, 0.4)
    >>> round(translational_decay_rate(K1, K2), 12)
    0.2
    """
    if eta <= 0:
        raise ValueError(f"eta must be > 0, got {eta}")
    K1 = eta / 2.0 if K1 is None else K1
    K2 = eta
    if K2**2 >= 4.0 * (K1 + 1.0):
        raise ValueError(
            "K2 = eta is not underdamped for this K1; the decay rate would differ from eta/2"
        )
    return K1, K2


def dwell_time_bound(
    eta: float,
    S: float,
    zeta: float,
    D: float,
    eps: float,
    eps1: float,
    tau: float = 0.0,
    s_offset: float = 2.0,
) -> float:
    """Right side of (21): ``max[(2/eta) ln((eps + (S + 2) zeta D)/eps1), tau]`` [s].

    ``s_offset = 1`` gives the proof-consistent variant with (S + 1) (E001-07).

    Parameters
    ----------
    eta : float
        Decay rate (> 0) [1/s].
    S : float
        Largest variation-matrix norm [-].
    zeta : float
        zeta of (20) [-].
    D : float
        Disturbance bound (Definition 1) [N, N m].
    eps, eps1 : float
        The bounds eps and eps1 (> 0) of Theorem 1 [-].
    tau : float, optional
        Lower limit of the bound [s].
    s_offset : float, optional
        The 2 of (S + 2) (1: the proof-consistent variant, E001-07) [-].

    Returns
    -------
    float
        The dwell-time bound [s].

    Raises
    ------
    ValueError
        ``eta <= 0`` or ``eps1 <= 0``.

    Examples
    --------
    >>> from formation_ftc.design.dwell_time import dwell_time_bound
    >>> round(dwell_time_bound(eta=0.4, S=2.0, zeta=0.5, D=0.1, eps=1.0, eps1=0.5), 6)
    4.377344
    >>> dwell_time_bound(eta=0.4, S=2.0, zeta=0.5, D=0.1, eps=1.0, eps1=0.5, tau=10.0)
    10.0
    """
    if eta <= 0 or eps1 <= 0:
        raise ValueError(f"(21) needs eta > 0 and eps1 > 0, got eta={eta}, eps1={eps1}")
    return float(max(2.0 / eta * np.log((eps + (S + s_offset) * zeta * D) / eps1), tau))


def new_state_bound(eps2: float, zeta: float, D: float) -> float:
    """Right side of (22): ``eps2 + zeta D``.

    Parameters
    ----------
    eps2 : float
        eps2 of Theorem 1 [-].
    zeta : float
        zeta of (20) [-].
    D : float
        Disturbance bound [N, N m].

    Returns
    -------
    float
        The bound on a joining spacecraft's state norm [-].

    Examples
    --------
    >>> from formation_ftc.design.dwell_time import new_state_bound
    >>> new_state_bound(0.2, 0.5, 0.1)
    0.25
    """
    return float(eps2 + zeta * D)


def initial_state_bound(eps: float, S: float, zeta: float, D: float) -> float:
    """Right side of (24): ``eps + (S + 1) zeta D``.

    Parameters
    ----------
    eps : float
        eps of Theorem 1 [-].
    S : float
        Largest variation-matrix norm [-].
    zeta : float
        zeta of (20) [-].
    D : float
        Disturbance bound [N, N m].

    Returns
    -------
    float
        The bound on |X(0)| [-].

    Examples
    --------
    >>> from formation_ftc.design.dwell_time import initial_state_bound
    >>> initial_state_bound(1.0, 2.0, 0.5, 0.1)
    1.15
    """
    return float(eps + (S + 1.0) * zeta * D)


def state_envelope(eps: float, S: float, zeta: float, D: float) -> float:
    """Guaranteed bound of Theorem 1: ``|X(t)| <= eps + (S + 2) zeta D`` for all t.

    Parameters
    ----------
    eps : float
        eps of Theorem 1 [-].
    S : float
        Largest variation-matrix norm [-].
    zeta : float
        zeta of (20) [-].
    D : float
        Disturbance bound [N, N m].

    Returns
    -------
    float
        The guaranteed bound on |X(t)| [-].

    Examples
    --------
    >>> from formation_ftc.design.dwell_time import state_envelope
    >>> state_envelope(1.0, 2.0, 0.5, 0.1)
    1.2
    """
    return float(eps + (S + 2.0) * zeta * D)


def pre_switch_bound(eps1: float, zeta: float, D: float) -> float:
    """Bound at every switching instant, ``|X(t_k^-)| <= eps1 + zeta D`` (proof of Theorem 1).

    Parameters
    ----------
    eps1 : float
        eps1 of Theorem 1 [-].
    zeta : float
        zeta of (20) [-].
    D : float
        Disturbance bound [N, N m].

    Returns
    -------
    float
        The bound on |X(t_k^-)| [-].

    Examples
    --------
    >>> from formation_ftc.design.dwell_time import pre_switch_bound
    >>> pre_switch_bound(0.5, 0.5, 0.1)
    0.55
    """
    return float(eps1 + zeta * D)


def condition_29_margin(eta: float, eta1: float, dt1: float, dt2: float) -> float:
    """Left side of (29): ``(eta/2) dt1 - (eta1/2) dt2`` (>= 0 means tolerable by switching).

    Parameters
    ----------
    eta : float
        Decay rate of the healthy modes [1/s].
    eta1 : float
        Growth rate of the faulty mode [1/s].
    dt1 : float
        Time spent in the healthy modes [s].
    dt2 : float
        Time spent in the faulty mode [s].

    Returns
    -------
    float
        The margin [-].

    Examples
    --------
    >>> from formation_ftc.design.dwell_time import condition_29_margin
    >>> condition_29_margin(eta=0.4, eta1=0.2, dt1=10.0, dt2=15.0)
    0.5
    """
    return float(0.5 * eta * dt1 - 0.5 * eta1 * dt2)


def check_epsilons(eps: float, eps1: float, eps2: float, S: float) -> list[Inequality]:
    """Side conditions of Theorem 1: ``0 <= eps2 < eps``, ``eps1 > 0``, ``S eps1 + eps2 <= eps``.

    Parameters
    ----------
    eps, eps1, eps2 : float
        The bounds of Theorem 1 [-].
    S : float
        Largest variation-matrix norm [-].

    Returns
    -------
    list of Inequality
        The four side conditions, each with its truth value.

    Examples
    --------
    >>> from formation_ftc.design.dwell_time import check_epsilons
    >>> [c.holds for c in check_epsilons(eps=1.0, eps1=0.3, eps2=0.5, S=2.0)]
    [True, True, True, False]
    >>> print(check_epsilons(eps=1.0, eps1=0.3, eps2=0.5, S=2.0)[3])
    Thm 1 S eps1 + eps2 <= eps: 1.1 <= 1 (VIOLATED)
    """
    return [
        _inequality("eps2 >= 0", "Thm 1", eps2, ">=", 0.0),
        _inequality("eps2 < eps", "Thm 1", eps2, "<", eps),
        _inequality("eps1 > 0", "Thm 1", eps1, ">", 0.0),
        _inequality("S eps1 + eps2 <= eps", "Thm 1", S * eps1 + eps2, "<=", eps),
    ]


def check_dwell_time(
    min_activation: float,
    eta: float,
    S: float,
    zeta: float,
    D: float,
    eps: float,
    eps1: float,
    tau: float,
) -> Inequality:
    """(21): the shortest activation time of the switching modes must reach the bound.

    Parameters
    ----------
    min_activation : float
        Shortest activation time of the switching modes [s].
    eta, S, zeta, D, eps, eps1, tau : float
        As in :func:`dwell_time_bound` ([1/s], [-], [-], [N, N m], [-], [-], [s]).

    Returns
    -------
    Inequality
        ``min_activation >= dwell-time bound``.

    Examples
    --------
    >>> from formation_ftc.design.dwell_time import check_dwell_time
    >>> print(check_dwell_time(5.0, eta=0.4, S=2.0, zeta=0.5, D=0.1, eps=1.0, eps1=0.5, tau=0.0))
    (21) min Delta t >= dwell-time bound: 5 >= 4.37734 (holds)
    """
    bound = dwell_time_bound(eta, S, zeta, D, eps, eps1, tau)
    return _inequality(
        "min Delta t >= dwell-time bound", "(21)", float(min_activation), ">=", bound
    )


def check_new_state(norm: float, eps2: float, zeta: float, D: float, who: str = "") -> Inequality:
    """(22): ``|X*(t_k)| <= eps2 + zeta D`` for a joining spacecraft state.

    Parameters
    ----------
    norm : float
        |X*(t_k)| of the joining spacecraft [-].
    eps2, zeta, D : float
        As in :func:`new_state_bound` ([-], [-], [N, N m]).
    who : str, optional
        Name of the spacecraft, added to the inequality's name.

    Returns
    -------
    Inequality
        ``norm <= eps2 + zeta D``.

    Examples
    --------
    >>> from formation_ftc.design.dwell_time import check_new_state
    >>> print(check_new_state(0.3, eps2=0.2, zeta=0.5, D=0.1, who="spacecraft 5"))
    (22) |X*| <= eps2 + zeta D (spacecraft 5): 0.3 <= 0.25 (VIOLATED)
    """
    name = f"|X*| <= eps2 + zeta D{(' (' + who + ')') if who else ''}"
    return _inequality(name, "(22)", float(norm), "<=", new_state_bound(eps2, zeta, D))


def check_initial_state(norm: float, eps: float, S: float, zeta: float, D: float) -> Inequality:
    """(24): ``|X(0)| <= eps + (S + 1) zeta D``.

    Parameters
    ----------
    norm : float
        |X(0)| [-].
    eps, S, zeta, D : float
        As in :func:`initial_state_bound` ([-], [-], [-], [N, N m]).

    Returns
    -------
    Inequality
        ``norm <= eps + (S + 1) zeta D``.

    Examples
    --------
    >>> from formation_ftc.design.dwell_time import check_initial_state
    >>> check_initial_state(1.0, eps=1.0, S=2.0, zeta=0.5, D=0.1).holds
    True
    """
    bound = initial_state_bound(eps, S, zeta, D)
    return _inequality("|X(0)| <= eps + (S+1) zeta D", "(24)", float(norm), "<=", bound)


def check_condition_29(eta: float, eta1: float, dt1: float, dt2: float) -> Inequality:
    """(29): ``(eta/2) dt1 - (eta1/2) dt2 >= 0``.

    Parameters
    ----------
    eta, eta1, dt1, dt2 : float
        As in :func:`condition_29_margin` ([1/s], [1/s], [s], [s]).

    Returns
    -------
    Inequality
        ``margin >= 0``, with the inputs in its ``detail``.

    Examples
    --------
    >>> from formation_ftc.design.dwell_time import check_condition_29
    >>> c = check_condition_29(eta=0.4, eta1=0.2, dt1=10.0, dt2=15.0)
    >>> print(c)
    (29) (eta/2) dt1 - (eta1/2) dt2 >= 0: 0.5 >= 0 (holds)
    >>> c.detail
    'dt1 = 10 s, dt2 = 15 s, eta = 0.4, eta1 = 0.2'
    """
    margin = condition_29_margin(eta, eta1, dt1, dt2)
    detail = f"dt1 = {dt1:.6g} s, dt2 = {dt2:.6g} s, eta = {eta:g}, eta1 = {eta1:g}"
    return _inequality("(eta/2) dt1 - (eta1/2) dt2 >= 0", "(29)", margin, ">=", 0.0, detail)
