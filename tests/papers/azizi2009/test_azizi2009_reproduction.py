"""Reduced reproduction run (20 s horizon, alpha_2 grid step 1.0, 2 seeds): the report has the summary
keys of issue 5, every published value as a row with a verdict, the theory relations as rows, and the
figures 2-4 as PNG files. The full study (300 s, 0.1 grid, 20 seeds) is run by
``formation-ftc reproduce azizi2009``."""

import numpy as np
import pytest

from formation_ftc.papers.azizi2009.alpha2_study import alpha_min_on_grid
from formation_ftc.papers.azizi2009.reproduction import REPRODUCTION

KEYS = [
    "max_err_fault_free",
    "max_err_llfr",
    "alpha2_min_simulated",
    "alpha2_analytic_pi_0",
    "alpha2_analytic_pi_0.15",
    "alpha2_analytic_pi_0.2",
    "alpha2_analytic_pi_0.4",
]


def test_alpha_min_on_grid():
    a = np.array([1.0, 2.0, 3.0])
    assert alpha_min_on_grid(a, np.array([0.05, 0.03, 0.01]), 0.03) == 2.0
    assert alpha_min_on_grid(a, np.array([0.05, 0.04, 0.031]), 0.03) is None


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("azizi2009")
    reduced = {"simulation.horizon": 20.0, "sweep_step": 1.0, "seeds": 2}
    return REPRODUCTION.run(out, overrides=reduced), out


def test_summary_keys_and_values(report):
    rep, _ = report
    for k in KEYS:
        assert k in rep.summary and rep.summary[k] is not None
    s = rep.summary
    assert (
        s["alpha2_analytic_pi_0"]
        > s["alpha2_analytic_pi_0.15"]
        > s["alpha2_analytic_pi_0.2"]
        > s["alpha2_analytic_pi_0.4"]
    )
    assert s["alpha2_analytic_pi_0"] == pytest.approx(
        4.72, abs=6e-3
    )  # design is horizon-independent (300 s)
    assert s["max_err_llfr"] > 0.03 > s["max_err_analytic_alpha2_pi_0"]
    assert s["seed_spread"]["seeds"] == 2


def test_rows_cover_published_values_and_relations(report, recheck_verdicts):
    rep, _ = report
    recheck_verdicts(rep.rows)
    pubs = {r.published.split(" (")[0] for r in rep.rows}
    for v in ("about 1e-4 m", "0.072 m", "5.6", "7.6", "6.0", "5.4", "3.4"):
        assert v in pubs
    rel = [r for r in rep.rows if r.quantity.startswith("relation")]
    assert len(rel) >= 5
    assert all(r.verdict in {"match", "differs", "not stated"} for r in rep.rows)
    assert all(
        r.note for r in rep.rows if r.verdict == "differs"
    )  # every difference has its reason


def test_figures_written(report):
    rep, out = report
    assert sorted(f.number for f in rep.figures) == ["2", "3", "4"]
    for f in rep.figures:
        assert (out / f.path).stat().st_size > 10_000


def test_registration():
    assert REPRODUCTION.paper == "azizi2009"
    assert any(e[0] == "E004-08" for e in REPRODUCTION.errata)
