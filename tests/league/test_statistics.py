"""The confidence of a league ranking (issue 48, item 1): intervals, paired tests, Holm and tie groups.

Truths: scipy's exact binomial test on the discordant pairs and statsmodels' McNemar, Wilson interval
and Holm adjustment called directly; scipy's Wilcoxon signed-rank test; constructed tables whose
separation is known by construction (a method that passes every run against one that passes half;
methods one discordant pair apart). No league runs.
"""

from __future__ import annotations

import doctest
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy import stats
from statsmodels.stats.contingency_tables import mcnemar
from statsmodels.stats.multitest import multipletests
from statsmodels.stats.proportion import proportion_confint

from formation_ftc.league import report as lr
from formation_ftc.league import statistics as st
from formation_ftc.league.definition import builtin_leagues

DEFINITION = (
    Path(builtin_leagues()["translational"]).parent / "league-translational.toml"
).read_text()


def test_docstring_examples_run():
    assert doctest.testmod(st, optionflags=doctest.ELLIPSIS).failed == 0


def _paired(both: int, a_only: int, b_only: int, neither: int) -> tuple[np.ndarray, np.ndarray]:
    a = np.array([1] * both + [1] * a_only + [0] * b_only + [0] * neither, dtype=bool)
    b = np.array([1] * both + [0] * a_only + [1] * b_only + [0] * neither, dtype=bool)
    return a, b


@pytest.mark.parametrize("counts", [(40, 9, 2, 49), (10, 1, 0, 5), (3, 0, 7, 0), (50, 30, 18, 2)])
def test_mcnemar_is_the_exact_binomial_test_on_the_discordant_pairs(counts):
    both, b, c, neither = counts
    pa, pb = _paired(*counts)
    r = st.paired_comparison(pa, pb, np.zeros(pa.size), np.zeros(pa.size))
    assert r["test"] == "mcnemar" and (r["a_only"], r["b_only"]) == (b, c)
    assert r["pairs"] == sum(counts) and r["statistic"] == min(b, c)
    assert r["p_value"] == pytest.approx(stats.binomtest(b, b + c, 0.5).pvalue, rel=1e-12)
    table = np.array([[both, b], [c, neither]])
    assert r["p_value"] == pytest.approx(mcnemar(table, exact=True).pvalue, rel=1e-12)


def test_equal_pass_rates_compare_the_metric_with_wilcoxon():
    rng = np.random.default_rng(3)
    pa, pb = _paired(20, 3, 3, 4)
    ma = rng.uniform(0.1, 2.0, pa.size)
    mb = ma + rng.normal(0.05, 0.1, pa.size)
    ma[0] = mb[1] = np.nan  # did not finish: left out
    r = st.paired_comparison(pa, pb, ma, mb)
    both = np.isfinite(ma) & np.isfinite(mb)
    want = stats.wilcoxon(ma[both] - mb[both])
    assert r["test"] == "wilcoxon" and r["pairs"] == int(both.sum()) == pa.size - 2
    assert r["p_value"] == pytest.approx(want.pvalue) and r["statistic"] == want.statistic
    # every difference zero, or no pair where both finished: p = 1
    assert st.paired_comparison(pa, pb, ma, ma)["p_value"] == 1.0
    nan = np.full(pa.size, np.nan)
    r = st.paired_comparison(pa, pb, nan, mb)
    assert r["p_value"] == 1.0 and r["pairs"] == 0


@pytest.mark.parametrize("value", [True, False])
def test_a_degenerate_bootstrap_falls_back_to_wilson_over_the_seeds(value):
    seeds = np.repeat(np.arange(12), 5)  # 12 seeds x 5 cases
    passed = np.full(seeds.size, value)
    r = st.pass_rate_interval(passed, seeds)
    low, high = proportion_confint(12 * value, 12, alpha=0.05, method="wilson")
    assert r["method"] == "wilson" and r["seeds"] == 12
    assert (r["low"], r["high"]) == pytest.approx((low, high), rel=1e-12)
    # n is the number of seeds, not of runs: wider than Wilson over the 60 runs
    low60, high60 = proportion_confint(60 * value, 60, alpha=0.05, method="wilson")
    assert r["high"] - r["low"] > high60 - low60


def test_cluster_bootstrap_is_wider_than_wilson_over_runs_when_seeds_are_correlated():
    """40 seeds x 8 cases; a seed passes all its cases or none (perfect correlation within a seed),
    28 of 40 pass: 320 runs carry the information of 40."""
    seeds = np.repeat(np.arange(40), 8)
    passed = seeds < 28
    r = st.pass_rate_interval(passed, seeds)
    assert r["method"] == "cluster bootstrap" and r["estimate"] == pytest.approx(0.7)
    assert r["low"] <= r["estimate"] <= r["high"]
    low, high = proportion_confint(int(passed.sum()), passed.size, alpha=0.05, method="wilson")
    assert r["high"] - r["low"] > 1.5 * (high - low)
    # the bootstrap's seed is fixed: the same interval every call
    assert st.pass_rate_interval(passed, seeds) == r
    # the same fraction over independent runs (every seed passes 70 % of its cases): about as wide
    # as Wilson over the runs, much narrower than the clustered case
    mixed = (np.arange(320) % 10) < 7
    r2 = st.pass_rate_interval(mixed, np.arange(320))
    assert r2["high"] - r2["low"] < 0.6 * (r["high"] - r["low"])


def test_median_interval():
    rng = np.random.default_rng(1)
    v = rng.lognormal(0.0, 0.5, 200)
    low, high = st.median_interval(np.append(v, [np.nan, np.inf]))
    want = stats.bootstrap(
        (v,),
        np.median,
        n_resamples=st.N_RESAMPLES,
        method="percentile",
        random_state=np.random.default_rng(st.BOOTSTRAP_SEED),
    ).confidence_interval
    assert (low, high) == pytest.approx((want.low, want.high))
    assert low < np.median(v) < high
    assert all(math.isnan(x) for x in st.median_interval(np.array([1.0, np.nan])))
    # seeds x cases: contains the median over cases of the per-case medians
    m = rng.lognormal(0.0, 0.5, (50, 4)) * np.array([1.0, 2.0, 4.0, 8.0])
    m[3, 1] = np.nan
    low, high = st.median_interval(m)
    assert low < np.median(np.nanmedian(m, axis=0)) < high


def test_holm_is_statsmodels_multipletests():
    p = [0.001, 0.04, 0.03, 0.5, 0.012]
    assert st.holm(p) == pytest.approx(multipletests(p, method="holm")[1])
    assert st.holm([]).size == 0


def test_tie_groups():
    ranks = st.tie_groups([True, False, False])
    assert [r["rank"] for r in ranks] == [1, 2, 2, 2]
    assert [r["rank_display"] for r in ranks] == ["1", "2=", "2=", "2="]
    assert [r["tied"] for r in ranks] == [False, True, True, True]
    assert [r["rank_display"] for r in st.tie_groups([False, True, False, True])] == [
        "1=",
        "1=",
        "3=",
        "3=",
        "5",
    ]
    assert st.tie_groups([]) == [{"rank": 1, "tied": False, "rank_display": "1"}]


def _runs() -> pd.DataFrame:
    """4 methods x 2 cases x 60 seeds: A passes every run; B passes seeds 0-29; C is B less one
    passing run, D is C less one more (each one discordant pair from the next)."""
    rows = []
    for method in "ABCD":
        for case in ("none", "bias"):
            for j in range(60):
                passed = {
                    "A": True,
                    "B": j < 30,
                    "C": j < 30 and not (case == "none" and j == 29),
                    "D": j < 30 and not (case == "none" and j in (28, 29)),
                }[method]
                rows.append(
                    {
                        "method": method,
                        "level": "limited",
                        "case": case,
                        "fault_kind": case,
                        "replicate": j,
                        "seed": 1000 + j,
                        "status": "ok",
                        "metric:rms_shape_error": 0.5 + 0.001 * j if passed else 2.0,
                        "metric:delta_v_total": 1.0,
                    }
                )
    return pd.DataFrame(rows)


def test_ranking_shows_intervals_comparisons_and_ties():
    meta = {"definition": DEFINITION}
    runs = _runs()
    cells = lr.cell_table(meta, runs)
    rows = lr.ranking(meta, cells, runs)["limited"]
    assert [r["method"] for r in rows] == list("ABCD")  # the order: pass rate, then median
    assert [r["rank"] for r in rows] == [1, 2, 2, 2]
    assert [r["rank_display"] for r in rows] == ["1", "2=", "2=", "2="]
    assert [r["tied"] for r in rows] == [False, True, True, True]
    assert rows[0]["test"] is None and rows[0]["separated"] is None
    assert [r["separated"] for r in rows[1:]] == [True, False, False]
    assert [(r["only_above_passed"], r["only_this_passed"]) for r in rows[1:]] == [
        (60, 0),
        (1, 0),
        (1, 0),
    ]
    p = [stats.binomtest(60, 60, 0.5).pvalue, 1.0, 1.0]
    assert [r["p_value"] for r in rows[1:]] == pytest.approx(p)
    assert [r["p_adjusted"] for r in rows[1:]] == pytest.approx(multipletests(p, method="holm")[1])
    # A passes every run: Wilson over its 60 seeds; B: a seed passes both cases or none
    assert rows[0]["pass_rate_interval"] == "wilson" and rows[0]["seeds"] == 60
    assert rows[0]["pass_rate_low"] == pytest.approx(proportion_confint(60, 60, method="wilson")[0])
    for r in rows:
        assert r["pass_rate_low"] <= r["pass_rate"] <= r["pass_rate_high"]
        assert (
            r["rms_shape_error_median_low"]
            <= r["rms_shape_error_median"]
            <= r["rms_shape_error_median_high"]
        )
    assert rows[1]["pass_rate_interval"] == "cluster bootstrap"
    # without the runs: the position, no ties claimed
    plain = lr.ranking(meta, cells)["limited"]
    assert [r["rank_display"] for r in plain] == ["1", "2", "3", "4"]
    assert "pass_rate_low" not in plain[0]


def test_every_format_of_a_ranking_shows_intervals_and_ties():
    from formation_ftc.exitcodes import jsonable

    meta = {"definition": DEFINITION}
    runs = _runs()
    cells = lr.cell_table(meta, runs)
    rank = lr.ranking(meta, cells, runs)
    board = {
        "league": "t",
        "version": 2,
        "battery": {"name": "v1", "version": 1},
        "seeds": 60,
        "requirement": {"metric": "rms_shape_error", "max": 1.0, "units": "m"},
        "ranking": rank,
        "cells": cells.to_dict("records"),
    }
    md = lr.markdown_summary(jsonable(board))
    b = rank["limited"][1]
    assert f"| 2= | B | 0.500 [{b['pass_rate_low']:.2f}, {b['pass_rate_high']:.2f}] |" in md
    assert "| 1 | A | 1.000 [0.94, 1.00] |" in md
    assert "Intervals: 95 %" in md and "random seed 48" in md and "Holm" in md
    frame = lr.ranking_frame(rank)
    assert frame["rank_display"].tolist() == ["1", "2=", "2=", "2="]
    assert frame["rank"].tolist() == [1, 2, 2, 2] and frame["tied"].tolist() == [0, 1, 1, 1]
    assert frame["separated"].isna().tolist() == [True, False, False, False]
    assert str(frame["pairs"].dtype) == "Int64"
