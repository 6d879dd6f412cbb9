"""Evaluation ``li2020-formation-errors``: the formation tracking and keeping errors of Li et al. 2020,
Sec. IV (errata E000-08), and the li2020 report's metric set.

* mu1 = (1/N) sum_i ||e_i1||                                  formation tracking error [m]
* mu2 (literal, E000-08) = |d12 - d13 + d12 - d34 + d24 - d34| with d_ij = ||rho_i - rho_j||: the
  printed formula has a stray "|", read as absolute-value bars around the signed sum; it vanishes at the
  desired square but is not a true shape metric. Defined for N = 4 only (NaN otherwise).
* mu2_vc = sum_{i<j} ||(rho_i - rho_iF) - (rho_j - rho_jF)||  virtual-centre formation-keeping error
  (the paper's Sec. II-B definition). The common desired centre offset cancels in the differences, so
  it equals sum_{i<j} ||e_i1 - e_j1||.

:class:`FormationErrors` evaluates them at every sample from the closed loop's ``position_error``
(true position minus desired) and ``position`` signals; :func:`li2020_metrics` are the metrics of a
Li2020 run, every one accumulated at every step inside the run; :func:`settle_time` and
:func:`max_over_window` reduce a recorded time series (numpy).
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import partial
from typing import TYPE_CHECKING

import jax.numpy as jnp
import numpy as np

from formation_ftc.components._registry import BuildContext, register
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import Evaluation, Signal, component
from formation_ftc.sim.contract import as_float

if TYPE_CHECKING:
    from formation_ftc.sim.metrics import Metric

__all__ = [
    "FormationErrors",
    "Li2020FormationErrorsSection",
    "li2020_metrics",
    "MU1_AT",
    "E000_04_WINDOW",
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
    >>> from formation_ftc.components.evaluations.li2020_formation_errors import mu1
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
    >>> from formation_ftc.components.evaluations.li2020_formation_errors import mu2_literal
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
    >>> from formation_ftc.components.evaluations.li2020_formation_errors import pairwise_error_sum
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
    >>> from formation_ftc.components.evaluations.li2020_formation_errors import mu2_virtual_centre
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
    >>> from formation_ftc.components.evaluations.li2020_formation_errors import settle_time
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
    >>> from formation_ftc.components.evaluations.li2020_formation_errors import max_over_window
    >>> max_over_window(np.arange(5.0), np.array([9.0, 1.0, 3.0, 2.0, 0.0]), t_lo=1.0)
    3.0
    >>> max_over_window(np.arange(5.0), np.zeros(5), t_lo=10.0)
    nan
    """
    m = (np.asarray(time) >= t_lo - 1e-9) & (np.asarray(time) <= t_hi + 1e-9)
    return float(np.max(np.asarray(signal)[m])) if m.any() else float("nan")


#: times [s] of the mu1_at_<t>s metrics (those within the horizon)
MU1_AT = (10.0, 20.0, 30.0, 100.0, 300.0, 1000.0, 3000.0)
#: window [s] of ``mu1_max_50_300s`` (the E000-04 comparison of the literal and corrected d_hat sign;
#: declared when the horizon reaches its end)
E000_04_WINDOW = (50.0, 300.0)


def li2020_metrics(horizon: float, adaptive: Mapping[str, str]) -> tuple[Metric, ...]:
    """The metrics of a Li2020 run (every step inside the run).

    Parameters
    ----------
    horizon : float
        The run's horizon T [s]: windows and samples relative to it (last 10 %, ``mu1_at_<t>s`` within
        it, the E000-04 window when T reaches its end).
    adaptive : mapping of str to str
        The law's adaptive parameters (recorded signals) -> their units: their final values and their
        values at 0.9 T are added (``li2020-adaptive``: m_hat, beta_hat, d_hat; ``sir-ftc``: b_hat).

    Returns
    -------
    tuple of Metric
        Final values, maxima, 1 m settling time of mu1 [s], delta-v [m/s], peak force [N], ...

    Examples
    --------
    >>> names = [m.name for m in li2020_metrics(100.0, {"b_hat": "N"})]
    >>> "mu1_at_100s" in names, "mu1_at_300s" in names, names[-2:]
    (True, False, ['b_hat_final', 'b_hat_at_90pct'])
    """
    from formation_ftc.sim.metrics import Metric

    T = float(horizon)
    # values at the horizon: "last" (read once after the loop, no per-step cost)
    m = [
        Metric("mu1_final", "mu1", "last", units="m"),
        Metric("mu2_final", "mu2", "last", units="m"),
        Metric("mu2_vc_final", "mu2_vc", "last", units="m"),
        Metric("mu1_max_last_10pct", "mu1", "max", units="m", start=as_float(0.9 * T)),
        Metric("settle_time_mu1_1m", "mu1", "settle", units="s", threshold=as_float(1.0)),
        Metric("mu1_max_after_50s", "mu1", "max", units="m", start=as_float(50.0)),
        Metric("delta_v_total", "delta_v", "last", spacecraft="sum", units="m s-1"),
    ]
    # the largest force component of the worst spacecraft
    largest = partial(Metric, norm=True, norm_ord="inf", spacecraft="max")
    m.append(largest("max_control_force", "command", "max", units="N"))
    m += [
        Metric(f"mu1_at_{int(tq)}s", "mu1", "at", units="m", start=as_float(tq))
        for tq in MU1_AT
        if tq <= T + 1e-9
    ]
    each = partial(Metric, spacecraft="each")  # one per spacecraft
    m += [
        each("delta_v", "delta_v", "last", units="m s-1"),
        each("position_error_final", "position_error", "last", norm=True, units="m"),
        each("velocity_error_final", "velocity_error", "last", norm=True, units="m s-1"),
    ]
    lo, hi = E000_04_WINDOW
    if T >= hi - 1e-9:
        m.append(
            Metric("mu1_max_50_300s", "mu1", "max", units="m", start=as_float(lo), end=as_float(hi))
        )
    m += [each(f"{n}_final", n, "last", units=u) for n, u in adaptive.items()]
    # value at the step t = 0.9 T (the adaptive parameters' drift over the last 10 % of the horizon)
    m += [
        each(f"{n}_at_90pct", n, "at", units=u, start=as_float(0.9 * T))
        for n, u in adaptive.items()
    ]
    return tuple(m)


class Li2020FormationErrorsSection(StrictModel):
    """No fields: mu1, mu2, mu2_vc and the li2020 metrics of the run's horizon."""


def _build(sec: Li2020FormationErrorsSection, ctx: BuildContext) -> FormationErrors:
    """The evaluation of ``[[evaluations]] type = "li2020-formation-errors"``; its metrics (with the
    adaptive parameters the controller's section declares, ``adaptive_parameters``) are appended to
    ``ctx.metrics``."""
    adaptive = getattr(ctx.section("controller"), "adaptive_parameters", {})
    ctx.metrics.extend(li2020_metrics(ctx.horizon, adaptive))
    return FormationErrors()


register(
    "evaluation",
    "li2020-formation-errors",
    Li2020FormationErrorsSection,
    _build,
    "Li2020 formation errors mu1, mu2 (literal), mu2_vc and the li2020 report's metrics",
)
