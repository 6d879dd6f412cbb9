"""Shared fixtures for the paper reproductions: re-check every verdict from its stated criterion; compare
two runs' metric dicts."""

from __future__ import annotations

import math
import re

import pytest


def _clause(rel, *args) -> bool:
    """Independent evaluation of one basis clause (not the registry's code)."""

    def num(x):
        return float(x)

    if rel == "true":
        return bool(args[0])
    if rel == "decreasing":
        seq = [num(v) for v in args[0]]
        return (
            len(seq) >= 2
            and all(b < a for a, b in zip(seq, seq[1:], strict=False))
            and not any(math.isnan(v) for v in seq)
        )
    a, b = num(args[0]), num(args[1])
    if math.isnan(a) or math.isnan(b):
        return False
    if rel == "<":
        return a < b
    if rel == "<=":
        return a <= b
    if rel == ">":
        return a > b
    if rel == ">=":
        return a >= b
    if rel == "abs<=":
        return abs(a - b) <= num(args[2])
    if rel == "rel<=":
        return abs(a - b) <= num(args[2]) * abs(b)
    raise AssertionError(f"unknown relation {rel!r}")


#: words that mark a number the paper did not print; such numbers belong in the "reference" column
_UNPRINTED = re.compile(r"SPEC|reviewer|reference run|not printed|E0\d\d-\d\d ref", re.IGNORECASE)


def recheck(rows) -> dict[str, int]:
    """Assert that every verdict follows from its basis and that the paper column holds printed values only.

    Returns the verdict counts.
    """
    counts = {"match": 0, "differs": 0, "not stated": 0}
    for r in rows:
        d = r.as_dict() if hasattr(r, "as_dict") else dict(r)
        counts[d["verdict"]] += 1
        assert not _UNPRINTED.search(d["published"] or ""), (d["quantity"], d["published"])
        if d["verdict"] == "not stated":
            continue
        assert d["basis"], (
            f"{d['quantity']}: verdict {d['verdict']!r} without a basis (written by hand?)"
        )
        want = "match" if all(_clause(*c) for c in d["basis"]) else "differs"
        assert d["verdict"] == want, (d["quantity"], d["verdict"], d["basis"])
    return counts


@pytest.fixture
def recheck_verdicts():
    """``recheck_verdicts(rows) -> counts``: every verdict recomputed from its stated criterion."""
    return recheck


def same_metrics(m1: dict[str, float], m20: dict[str, float], rtol: float = 1e-12) -> float:
    """Assert equal metric dicts: the same names, NaN where the other is NaN, otherwise equal to a relative
    ``rtol``; return the largest relative difference."""
    assert m1.keys() == m20.keys(), sorted(set(m1) ^ set(m20))
    worst = 0.0
    for k, a in m1.items():
        b = m20[k]
        if math.isnan(a):
            assert math.isnan(b), k
            continue
        assert b == pytest.approx(a, rel=rtol, abs=0.0), k
        worst = max(worst, abs(a - b) / abs(a) if a != 0 else abs(b))
    return worst


@pytest.fixture(name="same_metrics")
def same_metrics_fixture():
    """``same_metrics(m1, m2, rtol=1e-12) -> largest relative difference``: two runs' metric dicts agree
    (the record_every tests of every paper)."""
    return same_metrics
