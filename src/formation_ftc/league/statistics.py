"""Confidence of a league ranking: intervals of pass rates and medians, paired comparisons of adjacent
methods, the Holm correction and the tie groups they give (issue 48).

Every statistic comes from scipy or statsmodels; this module only arranges the data:

* :func:`pass_rate_interval` -- 95 % interval of a pass rate. The runs of one seed are not independent
  (a seed fixes the initial errors, the fault onset and the noise of every case), so the interval is a
  cluster bootstrap over seeds (``scipy.stats.bootstrap``, percentile method, of the mean over seeds of
  each seed's pass fraction); the Wilson interval over the seeds when the bootstrap is degenerate;
* :func:`median_interval` -- percentile bootstrap interval of a median (of one sample, or of the median
  over cases of per-case medians, resampling seeds);
* :func:`paired_comparison` -- two methods on the runs they share (paired by case and seed): the exact
  McNemar test on the discordant pairs when their pass rates differ, else the Wilcoxon signed-rank test
  on the requirement metric;
* :func:`holm` -- Holm's step-down adjustment of the p-values of one level's adjacent comparisons;
* :func:`tie_groups` -- the shared ranks of methods that are not separated.

scipy and statsmodels are imported inside the functions: importing the package stays cheap.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = [
    "ALPHA",
    "mcnemar_power",
    "BOOTSTRAP_SEED",
    "CONFIDENCE",
    "N_RESAMPLES",
    "holm",
    "median_interval",
    "method_note",
    "paired_comparison",
    "pass_rate_interval",
    "tie_groups",
]

#: confidence level of every interval
CONFIDENCE = 0.95
#: family-wise error rate of the adjacent comparisons of one level (Holm); adjusted p >= ALPHA: a tie
ALPHA = 0.05
#: bootstrap resamples per interval
N_RESAMPLES = 2000
#: seed of the bootstrap's random generator (every interval reproduces exactly)
BOOTSTRAP_SEED = 48


def _bootstrap(data: np.ndarray, statistic: Any, confidence: float, n_resamples: int, seed: int):
    from scipy import stats

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN slices of a resample
        warnings.simplefilter("ignore", DeprecationWarning)  # random_state -> rng (scipy >= 1.15)
        res = stats.bootstrap(
            (data,),
            statistic,
            n_resamples=n_resamples,
            confidence_level=confidence,
            method="percentile",
            vectorized=True,
            random_state=np.random.default_rng(seed),
        )
    return float(res.confidence_interval.low), float(res.confidence_interval.high)


def pass_rate_interval(
    passed: np.ndarray,
    seeds: np.ndarray,
    confidence: float = CONFIDENCE,
    n_resamples: int = N_RESAMPLES,
    random_state: int = BOOTSTRAP_SEED,
) -> dict[str, Any]:
    """Confidence interval of a pass rate whose runs are clustered by seed.

    Per seed the fraction of its runs that passed; the interval is the percentile bootstrap
    (``scipy.stats.bootstrap``) of the mean of those fractions over the seeds -- a cluster bootstrap:
    the runs of one seed share its initial errors, fault onset and noise, so they are resampled
    together. When every seed has the same fraction (all pass or all fail: the bootstrap distribution
    is one point), the Wilson score interval
    (``statsmodels.stats.proportion.proportion_confint(method="wilson")``) with n = the number of
    seeds, the independent units, takes its place.

    Parameters
    ----------
    passed : numpy.ndarray
        One bool per run: the run passed the requirement.
    seeds : numpy.ndarray
        One seed (or replicate) identifier per run, same length as ``passed``.
    confidence : float
        Confidence level (0.95: a 95 % interval).
    n_resamples : int
        Bootstrap resamples.
    random_state : int
        Seed of the bootstrap's random generator.

    Returns
    -------
    dict
        ``{"estimate", "low", "high"}`` (fractions, dimensionless; the estimate is the mean over seeds
        of the per-seed pass fractions), ``"method"`` (``"cluster bootstrap"`` or ``"wilson"``) and
        ``"seeds"`` (number of seeds). NaN bounds for no runs.

    Examples
    --------
    >>> import numpy as np
    >>> passed = np.array([1, 1, 0, 1, 0, 0, 1, 0], dtype=bool)
    >>> seeds = np.array([0, 0, 1, 1, 2, 2, 3, 3])
    >>> r = pass_rate_interval(passed, seeds)
    >>> r["method"], r["seeds"], r["estimate"], r["low"] <= r["estimate"] <= r["high"]
    ('cluster bootstrap', 4, 0.5, True)
    >>> r = pass_rate_interval(np.ones(6, dtype=bool), np.array([0, 0, 1, 1, 2, 2]))
    >>> r["method"], round(r["low"], 3), r["high"]
    ('wilson', 0.439, 1.0)
    """
    passed = np.asarray(passed, dtype=float)
    seeds = np.asarray(seeds)
    if passed.shape != seeds.shape or passed.ndim != 1:
        raise ValueError(f"passed {passed.shape} and seeds {seeds.shape}: one of each per run")
    if not passed.size:
        return {"estimate": math.nan, "low": math.nan, "high": math.nan, "method": "", "seeds": 0}
    _, inverse = np.unique(seeds, return_inverse=True)
    fraction = np.bincount(inverse, weights=passed) / np.bincount(inverse)
    n = int(fraction.size)
    estimate = float(fraction.mean())
    if n < 2 or np.all(fraction == fraction[0]):
        from statsmodels.stats.proportion import proportion_confint

        low, high = proportion_confint(estimate * n, n, alpha=1 - confidence, method="wilson")
        # (statsmodels' upper bound at 1 is 1 - 2e-16: the bounds hold the estimate)
        low, high, method = min(float(low), estimate), max(float(high), estimate), "wilson"
    else:
        low, high = _bootstrap(fraction, np.mean, confidence, n_resamples, random_state)
        method = "cluster bootstrap"
    return {"estimate": estimate, "low": low, "high": high, "method": method, "seeds": n}


def median_interval(
    values: np.ndarray,
    confidence: float = CONFIDENCE,
    n_resamples: int = N_RESAMPLES,
    random_state: int = BOOTSTRAP_SEED,
) -> tuple[float, float]:
    """Percentile bootstrap interval (``scipy.stats.bootstrap``) of a median, in the values' units.

    A 1-D ``values``: the median of its finite values, resampling those values. A 2-D ``values``
    (seeds x cases, NaN where a run did not finish or is missing): the median over cases of the
    per-case medians -- the statistic a league ranking shows -- resampling whole seeds (rows), as
    :func:`pass_rate_interval` does.

    Parameters
    ----------
    values : numpy.ndarray
        The sample (1-D), or one row per seed and one column per case (2-D).
    confidence : float
        Confidence level.
    n_resamples : int
        Bootstrap resamples.
    random_state : int
        Seed of the bootstrap's random generator.

    Returns
    -------
    tuple of float
        ``(low, high)``; ``(nan, nan)`` with fewer than 2 finite values (2-D: fewer than 2 seeds with
        a finite value).

    Examples
    --------
    >>> import numpy as np
    >>> low, high = median_interval(np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0, np.nan]))
    >>> bool(low <= 3.5 <= high)
    True
    >>> median_interval(np.array([2.0]))
    (nan, nan)
    >>> m = np.array([[1.0, 10.0], [2.0, 20.0], [3.0, np.nan], [4.0, 40.0]])
    >>> low, high = median_interval(m)
    >>> bool(low <= 10.25 <= high)
    True
    """
    v = np.asarray(values, dtype=float)
    v = np.where(np.isfinite(v), v, np.nan)
    if v.ndim == 1:
        v = v[np.isfinite(v)]
        if v.size < 2:
            return math.nan, math.nan
        return _bootstrap(v, np.median, confidence, n_resamples, random_state)
    if v.ndim != 2:
        raise ValueError(f"values of shape {v.shape}: 1-D, or 2-D (seeds x cases)")
    v = v[np.isfinite(v).any(axis=1)]
    if v.shape[0] < 2:
        return math.nan, math.nan

    def median_of_medians(rows: np.ndarray, axis: int = -1) -> np.ndarray:
        picked = v[rows.astype(np.intp)]  # (..., seeds, cases)
        return np.nanmedian(np.nanmedian(picked, axis=-2), axis=-1)

    return _bootstrap(
        np.arange(v.shape[0]), median_of_medians, confidence, n_resamples, random_state
    )


def paired_comparison(
    passed_a: np.ndarray, passed_b: np.ndarray, metric_a: np.ndarray, metric_b: np.ndarray
) -> dict[str, Any]:
    """Compare two methods on their paired runs (same case, same seed; element k of every array is
    pair k).

    When their pass rates over the pairs differ: the exact McNemar test on the discordant pairs
    (``statsmodels.stats.contingency_tables.mcnemar(table, exact=True)``: the two-sided binomial test
    of b against b + c at 1/2). When the pass rates are equal: the Wilcoxon signed-rank test
    (``scipy.stats.wilcoxon``) of the requirement metric over the pairs where both runs finished
    (finite metric), p = 1 when there is no such pair or every difference is zero.

    Parameters
    ----------
    passed_a, passed_b : numpy.ndarray
        One bool per pair: the run of method a (b) passed.
    metric_a, metric_b : numpy.ndarray
        The requirement metric of each run (its units; NaN for a run that did not finish).

    Returns
    -------
    dict
        ``test`` (``"mcnemar"`` or ``"wilcoxon"``), ``statistic`` (McNemar: min(b, c); Wilcoxon: the
        signed-rank statistic; NaN when not computed), ``p_value``, ``pairs`` (the pairs compared),
        ``a_only`` (b: pairs where only a passed), ``b_only`` (c: only b passed).

    Examples
    --------
    >>> import numpy as np
    >>> a = np.array([1, 1, 1, 1, 1, 1, 1, 0, 1, 1], dtype=bool)
    >>> b = np.array([0, 0, 0, 0, 0, 0, 1, 1, 1, 1], dtype=bool)
    >>> r = paired_comparison(a, b, np.zeros(10), np.zeros(10))
    >>> r["test"], r["a_only"], r["b_only"], round(r["p_value"], 4)
    ('mcnemar', 6, 1, 0.125)
    >>> r = paired_comparison(a, a, np.arange(10.0), np.arange(10.0) + 1)
    >>> r["test"], round(r["p_value"], 4)
    ('wilcoxon', 0.002)
    """
    pa = np.asarray(passed_a, dtype=bool)
    pb = np.asarray(passed_b, dtype=bool)
    ma = np.asarray(metric_a, dtype=float)
    mb = np.asarray(metric_b, dtype=float)
    if not (pa.shape == pb.shape == ma.shape == mb.shape) or pa.ndim != 1:
        raise ValueError("passed_a, passed_b, metric_a, metric_b: one value per pair each")
    a_only = int(np.sum(pa & ~pb))
    b_only = int(np.sum(~pa & pb))
    out: dict[str, Any] = {"pairs": int(pa.size), "a_only": a_only, "b_only": b_only}
    if a_only != b_only:
        from statsmodels.stats.contingency_tables import mcnemar

        table = np.array([[np.sum(pa & pb), a_only], [b_only, np.sum(~pa & ~pb)]])
        test, res = "mcnemar", mcnemar(table, exact=True)
    else:
        both = np.isfinite(ma) & np.isfinite(mb)
        d = ma[both] - mb[both]
        out["pairs"] = int(both.sum())
        if d.size < 1 or np.all(d == 0):
            return {"test": "wilcoxon", "statistic": math.nan, "p_value": 1.0} | out
        from scipy.stats import wilcoxon

        with warnings.catch_warnings():  # small samples, ties: normal approximation
            warnings.simplefilter("ignore", UserWarning)
            test, res = "wilcoxon", wilcoxon(d)
    return {"test": test, "statistic": float(res.statistic), "p_value": float(res.pvalue)} | out


def mcnemar_power(pairs: int, discordant: float, difference: float, alpha: float) -> float:
    """Exact power of the two-sided exact McNemar test (:func:`paired_comparison`) at level ``alpha``
    on ``pairs`` paired runs, when the two pass rates differ by ``difference`` and a fraction
    ``discordant`` of the pairs is discordant.

    The discordant pairs D are Binomial(pairs, psi) with psi = max(discordant, difference) (a
    difference needs at least that many); given D, the pairs where only the better method passed are
    Binomial(D, (psi + difference) / (2 psi)), and the test rejects when min(b, D - b) <= c_D, the
    largest c with 2 P(Binomial(D, 1/2) <= c) <= alpha. The power sums the rejection probability over
    D (``scipy.stats.binom``; no simulation).

    Parameters
    ----------
    pairs : int
        Paired runs (same case and seed) [-].
    discordant : float
        Fraction of discordant pairs (one passed, the other failed) [-].
    difference : float
        Difference of the pass rates to detect, in (0, 1] [-].
    alpha : float
        Level of the test (e.g. the Holm family's alpha over its comparisons) [-].

    Returns
    -------
    float
        The probability that the test separates the two methods [-].

    Examples
    --------
    >>> round(mcnemar_power(700, 0.0, 0.1, 0.05), 3)
    1.0
    >>> mcnemar_power(10, 0.5, 0.1, 0.05) < 0.1
    True
    """
    from scipy.stats import binom

    if pairs < 1:
        return 0.0
    if not 0 < difference <= 1:
        raise ValueError(f"difference = {difference}: a pass-rate difference in (0, 1]")
    psi = min(1.0, max(float(discordant), float(difference)))
    d = np.arange(pairs + 1)
    # c_D: the largest c with 2 P(B(D, 1/2) <= c) <= alpha (-1: no b rejects)
    c = binom.ppf(alpha / 2, d, 0.5).astype(int)
    c = np.where(2 * binom.cdf(c, d, 0.5) <= alpha, c, c - 1)
    q = (psi + difference) / (2 * psi)
    reject = np.where(c >= 0, binom.cdf(c, d, q) + binom.sf(np.maximum(d - c - 1, c), d, q), 0.0)
    return float(np.clip(np.sum(binom.pmf(d, pairs, psi) * reject), 0.0, 1.0))


def holm(p_values: Sequence[float]) -> np.ndarray:
    """Holm's step-down adjustment (``statsmodels.stats.multitest.multipletests(method="holm")``) of
    the p-values of one family (the adjacent comparisons of one level).

    Parameters
    ----------
    p_values : sequence of float
        Unadjusted p-values.

    Returns
    -------
    numpy.ndarray
        The adjusted p-values (same order; empty for none).

    Examples
    --------
    >>> holm([0.01, 0.04, 0.03]).round(3).tolist()
    [0.03, 0.06, 0.06]
    """
    p = np.asarray(p_values, dtype=float)
    if not p.size:
        return np.zeros(0)
    from statsmodels.stats.multitest import multipletests

    return np.asarray(multipletests(p, alpha=ALPHA, method="holm")[1], dtype=float)


def tie_groups(separated: Sequence[bool]) -> list[dict[str, Any]]:
    """Shared ranks of an ordered list of methods from the separation of adjacent ones.

    ``separated[k]`` says whether method k + 1 is separated from method k (its adjusted p-value is
    below :data:`ALPHA`). A maximal run of consecutive methods that are not separated is a tie group;
    every member gets the group's first position as its rank.

    Parameters
    ----------
    separated : sequence of bool
        One per adjacent pair (length: methods - 1).

    Returns
    -------
    list of dict
        One per method: ``rank`` (int, 1-based, shared by a group), ``tied`` (bool: in a group of two
        or more) and ``rank_display`` (``"3="`` for a tie, else ``"3"``).

    Examples
    --------
    >>> [r["rank_display"] for r in tie_groups([True, False, False])]
    ['1', '2=', '2=', '2=']
    >>> [r["rank"] for r in tie_groups([False, True, True])]
    [1, 1, 3, 4]
    """
    n = len(separated) + 1
    first = [1] * n
    for k in range(1, n):
        first[k] = k + 1 if separated[k - 1] else first[k - 1]
    size = {f: first.count(f) for f in set(first)}
    return [
        {"rank": f, "tied": size[f] > 1, "rank_display": f"{f}=" if size[f] > 1 else str(f)}
        for f in first
    ]


def method_note(seed: int = BOOTSTRAP_SEED, n_resamples: int = N_RESAMPLES) -> str:
    """The sentence under a ranking table: confidence level, methods and bootstrap seed.

    Parameters
    ----------
    seed : int
        Seed of the bootstrap's random generator.
    n_resamples : int
        Bootstrap resamples.

    Returns
    -------
    str
        One paragraph.

    Examples
    --------
    >>> method_note().startswith("Intervals: 95 %")
    True
    """
    return (
        f"Intervals: {CONFIDENCE * 100:g} % -- pass rate: cluster bootstrap over seeds (percentile, "
        "of the mean of the per-seed pass fractions; Wilson over the seeds when every seed has the same fraction), median: bootstrap "
        f"over seeds of the median over cases of the per-case medians; {n_resamples} resamples, "
        f"random seed {seed}. Adjacent methods are compared on their paired runs (same case and "
        "seed): exact McNemar test on the discordant pairs when their pass rates differ, else "
        "Wilcoxon signed-rank test on the requirement metric; p-values Holm-adjusted per level. "
        f"Methods not separated (adjusted p >= {ALPHA:g}) share a rank, shown as 3=."
    )
