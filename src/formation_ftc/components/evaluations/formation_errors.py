"""Formation tracking and keeping errors of Li et al. 2020, Sec. IV (errata E000-08).

* mu1 = (1/N) sum_i ||e_i1||                                  formation tracking error [m]
* mu2 (literal, E000-08) = |d12 - d13 + d12 - d34 + d24 - d34| with d_ij = ||rho_i - rho_j||: the
  printed formula has a stray "|", read as absolute-value bars around the signed sum; it vanishes at the
  desired square but is not a true shape metric. Defined for N = 4 only (NaN otherwise).
* mu2_vc = sum_{i<j} ||(rho_i - rho_iF) - (rho_j - rho_jF)||  virtual-centre formation-keeping error
  (the paper's Sec. II-B definition). The common desired centre offset cancels in the differences, so
  it equals sum_{i<j} ||e_i1 - e_j1||.

:class:`FormationErrors` evaluates them at every sample from the closed loop's ``position_error``
(true position minus desired) and ``position`` signals; :func:`settle_time` and
:func:`max_over_window` reduce a recorded time series (numpy).
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from formation_ftc.sim.components import Evaluation, Signal, component

__all__ = [
    "FormationErrors",
    "mu1",
    "mu2_literal",
    "mu2_virtual_centre",
    "pairwise_error_sum",
    "settle_time",
    "max_over_window",
]


def mu1(e1):
    """(1/N) sum ||e_i1|| [m]; e1 (..., N, 3).

    Parameters
    ----------
    e1 : array_like, shape (..., N, 3)
        Position errors e_i1 [m].

    Returns
    -------
    jax.Array, shape (...)
        mu1 [m].

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.evaluations.formation_errors import mu1
    >>> float(mu1(np.array([[3.0, 4.0, 0.0], [0.0, 0.0, 1.0]])))
    3.0
    """
    return jnp.mean(jnp.linalg.norm(e1, axis=-1), axis=-1)


def _d(rho, i, j):
    return jnp.linalg.norm(rho[..., i, :] - rho[..., j, :], axis=-1)


def mu2_literal(rho):
    """|d12 - d13 + d12 - d34 + d24 - d34| [m] (E000-08); rho (..., 4, 3); NaN when N != 4.

    Parameters
    ----------
    rho : array_like, shape (..., N, 3)
        Positions [m].

    Returns
    -------
    jax.Array, shape (...)
        The literal mu2 [m] (NaN unless N = 4).

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.evaluations.formation_errors import mu2_literal
    >>> square = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]])
    >>> float(mu2_literal(square))  # 0 at the desired square
    0.0
    >>> float(mu2_literal(square[:3]))
    nan
    """
    if rho.shape[-2] != 4:
        return jnp.full(rho.shape[:-2], jnp.nan)
    d12, d13, d34, d24 = _d(rho, 0, 1), _d(rho, 0, 2), _d(rho, 2, 3), _d(rho, 1, 3)
    return jnp.abs(d12 - d13 + d12 - d34 + d24 - d34)


def pairwise_error_sum(c):
    """sum_{i<j} ||c_i - c_j|| [m]; c (..., N, 3).

    Parameters
    ----------
    c : array_like, shape (..., N, 3)
        Position errors or positions [m].

    Returns
    -------
    jax.Array, shape (...)
        The sum over the N (N - 1) / 2 pairs [m].

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.evaluations.formation_errors import pairwise_error_sum
    >>> float(pairwise_error_sum(np.array([[0.0, 0.0, 0.0], [3.0, 4.0, 0.0], [3.0, 4.0, 0.0]])))
    10.0
    """
    n = c.shape[-2]
    iu, ju = np.triu_indices(n, k=1)
    return jnp.sum(jnp.linalg.norm(c[..., iu, :] - c[..., ju, :], axis=-1), axis=-1)


def mu2_virtual_centre(rho, rho_f):
    """sum_{i<j} ||(rho_i - rho_iF) - (rho_j - rho_jF)|| [m]; rho, rho_f (..., N, 3).

    Parameters
    ----------
    rho : array_like, shape (..., N, 3)
        Positions [m].
    rho_f : array_like, shape (..., N, 3)
        Desired positions [m].

    Returns
    -------
    jax.Array, shape (...)
        mu2_vc [m].

    Examples
    --------
    A common offset of the whole formation does not count:

    >>> import numpy as np
    >>> from formation_ftc.components.evaluations.formation_errors import mu2_virtual_centre
    >>> rho_f = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]])
    >>> float(mu2_virtual_centre(rho_f + 5.0, rho_f)), float(mu2_virtual_centre(rho_f * 1.1, rho_f))
    (0.0, 1.0)
    """
    return pairwise_error_sum(rho - rho_f)


@component
class FormationErrors(Evaluation):
    """Signals ``mu1``, ``mu2`` (literal) and ``mu2_vc`` [m] from ``position_error`` and ``position``."""

    def signals(self):
        return (
            Signal("mu1", (), "m", "formation tracking error (1/N) sum |e_i1|"),
            Signal("mu2", (), "m", "formation keeping error, literal printed formula (E000-08)"),
            Signal("mu2_vc", (), "m", "virtual-centre formation keeping error"),
        )

    def outputs(self, signals):
        e1, rho = signals["position_error"], signals["position"]
        return {"mu1": mu1(e1), "mu2": mu2_literal(rho), "mu2_vc": pairwise_error_sum(e1)}


def settle_time(time: np.ndarray, signal: np.ndarray, threshold: float) -> float:
    """First time after which ``signal`` stays below ``threshold`` (NaN if it ends above it) [s].

    Parameters
    ----------
    time : array_like, shape (T,)
        Sample times [s].
    signal : array_like, shape (T,)
        The signal (any unit).
    threshold : float
        Threshold (same unit as the signal).

    Returns
    -------
    float
        The settle time [s] (the first time when the signal never reaches the threshold).

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.evaluations.formation_errors import settle_time
    >>> t = np.arange(5.0)
    >>> settle_time(t, np.array([5.0, 2.0, 0.5, 0.2, 0.1]), threshold=1.0)
    2.0
    >>> settle_time(t, np.array([5.0, 2.0, 0.5, 0.2, 3.0]), threshold=1.0)
    nan
    """
    signal = np.asarray(signal)
    above = np.flatnonzero(~(signal < threshold))
    if above.size == 0:
        return float(time[0])
    last = above[-1]
    if last == len(signal) - 1:
        return float("nan")
    return float(time[last + 1])


def max_over_window(
    time: np.ndarray, signal: np.ndarray, t_lo: float, t_hi: float = np.inf
) -> float:
    """max of ``signal`` over t_lo <= t <= t_hi (NaN if the window is empty).

    Parameters
    ----------
    time : array_like, shape (T,)
        Sample times [s].
    signal : array_like, shape (T,)
        The signal (any unit).
    t_lo : float
        Window start [s] (inclusive to 1e-9 s).
    t_hi : float, optional
        Window end [s] (inclusive to 1e-9 s).

    Returns
    -------
    float
        The maximum (same unit as the signal).

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.evaluations.formation_errors import max_over_window
    >>> max_over_window(np.arange(5.0), np.array([9.0, 1.0, 3.0, 2.0, 0.0]), t_lo=1.0)
    3.0
    >>> max_over_window(np.arange(5.0), np.zeros(5), t_lo=10.0)
    nan
    """
    m = (np.asarray(time) >= t_lo - 1e-9) & (np.asarray(time) <= t_hi + 1e-9)
    return float(np.max(np.asarray(signal)[m])) if m.any() else float("nan")
