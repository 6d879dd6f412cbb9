"""Quasi-Monte Carlo campaign sampling (scrambled Sobol', Latin hypercube): the designs have the
stratification their definitions promise (checked by counting points in strata and elementary
boxes, not against SciPy's own output), each distribution is reached through its inverse CDF, and
run inputs keep the per-run determinism of the random sampler."""

from __future__ import annotations

import random

import numpy as np
import pytest
from scipy import stats

from formation_ftc.campaign import CampaignError, make_plan
from formation_ftc.campaign.sampling import qmc_design, value_from_unit
from formation_ftc.campaign.spec import parse_sampler


def _qmc(tiny, sampling, runs, **extra):
    raw = tiny(runs=runs, sampling=sampling, **extra)
    raw["sample"] = {
        "controller.kp": {"dist": "uniform", "low": 1.0, "high": 3.0},
        "controller.kd": {"dist": "loguniform", "low": 10.0, "high": 1000.0},
    }
    return make_plan(raw)


def _units(plan):
    """Back to the unit square: kp uniform on [1, 3], kd loguniform on [10, 1000]."""
    pts = [plan.run_inputs(r).values for r in range(plan.n_runs)]
    return np.array(
        [
            [(v["controller.kp"] - 1.0) / 2.0, (np.log10(v["controller.kd"]) - 1.0) / 2.0]
            for v in pts
        ]
    )


def _one_per_cell(u, cells):
    """Every cell of a (cells[0] x cells[1]) grid of the unit square holds exactly one point."""
    idx = np.floor(u * np.asarray(cells)).astype(int)
    counts = np.zeros(cells, int)
    np.add.at(counts, (idx[:, 0], idx[:, 1]), 1)
    return bool((counts == 1).all())


def test_sobol_first_16_runs_are_a_net(tiny):
    u = _units(_qmc(tiny, "sobol", 16))
    assert u.shape == (16, 2) and ((0 <= u) & (u < 1)).all()
    # a (0, 4, 2)-net in base 2: every elementary box of volume 1/16 holds exactly one point
    for cells in [(16, 1), (8, 2), (4, 4), (2, 8), (1, 16)]:
        assert _one_per_cell(u, cells), cells
    # pseudo-random points practically never are (probability 16!/16**16 ~ 1e-6 per 1-D partition)
    r = np.random.default_rng(0).uniform(size=(16, 2))
    assert not _one_per_cell(r, (16, 1))


def test_sobol_run_values_do_not_depend_on_runs_or_order(tiny):
    small, big = _qmc(tiny, "sobol", 8), _qmc(tiny, "sobol", 64)
    ids = list(range(8))
    random.Random(5).shuffle(ids)
    for r in ids:  # replicate j of grid point 0 is run j in both
        assert small.run_inputs(r) == big.run_inputs(r)
    assert _qmc(tiny, "sobol", 8).run_inputs(3) == small.run_inputs(3)  # reproducible
    # paired: replicate j has the same QMC point at both kd grid values... here kd is sampled, so one grid
    # point; the campaign seed changes the scrambling
    raw = tiny(runs=8, sampling="sobol", seed=12)
    raw["sample"] = {
        "controller.kp": {"dist": "uniform", "low": 1.0, "high": 3.0},
        "controller.kd": {"dist": "loguniform", "low": 10.0, "high": 1000.0},
    }
    assert make_plan(raw).run_inputs(3).values != small.run_inputs(3).values


def test_lhs_one_point_per_stratum_and_paired_grid(tiny):
    raw = tiny(runs=10, sampling="lhs")  # kp uniform, kd grid {10, 30}, mass.0 truncated normal
    plan = make_plan(raw)
    assert plan.n_runs == 20
    kp = np.array([plan.run_inputs(r).values["controller.kp"] for r in range(10)])
    mass = np.array([plan.run_inputs(r).values["plant.mass.0"] for r in range(10)])
    u_kp = (kp - 1.0) / 2.0
    assert sorted(np.floor(u_kp * 10).astype(int)) == list(range(10))
    # the truncated normal through its CDF: again one value per decile of its distribution
    a, b = (80.0 - 100.0) / 5.0, np.inf
    u_m = stats.truncnorm.cdf(mass, a, b, loc=100.0, scale=5.0)
    assert sorted(np.floor(u_m * 10 + 1e-9).astype(int)) == list(range(10))
    # paired = true: replicate j has the same sample at both grid points (common random numbers)
    for j in range(10):
        x, y = plan.run_inputs(j), plan.run_inputs(10 + j)
        assert x.values["controller.kd"] == 10.0 and y.values["controller.kd"] == 30.0
        assert x.values["controller.kp"] == y.values["controller.kp"] and x.seed == y.seed


def test_lhs_unpaired_spans_all_runs(tiny):
    plan = make_plan(tiny(runs=6, sampling="lhs", paired=False))
    kp = np.array([plan.run_inputs(r).values["controller.kp"] for r in range(plan.n_runs)])
    assert sorted(np.floor((kp - 1.0) / 2.0 * 12).astype(int)) == list(range(12))


def test_integer_and_choice_through_the_inverse_cdf(tiny):
    raw = tiny(runs=12, sampling="lhs")
    raw["sample"] = {
        "controller.kp": {"dist": "integer", "low": 1, "high": 4},
        "controller.kd": {"choice": [10.0, 20.0, 40.0], "weights": [1, 1, 2]},
    }
    plan = make_plan(raw)
    kp = [plan.run_inputs(r).values["controller.kp"] for r in range(12)]
    kd = [plan.run_inputs(r).values["controller.kd"] for r in range(12)]
    # 12 strata: each of the 4 integers gets exactly 3, the choices exactly 3 / 3 / 6 (weights 1:1:2)
    assert sorted(kp) == [1] * 3 + [2] * 3 + [3] * 3 + [4] * 3
    assert sorted(kd) == [10.0] * 3 + [20.0] * 3 + [40.0] * 6
    assert all(isinstance(k, int) for k in kp)


def test_value_from_unit_matches_closed_forms():
    u = np.array([0.0, 0.1, 0.5, 0.9, 0.999])
    uni = parse_sampler("a", {"dist": "uniform", "low": 2.0, "high": 6.0})
    assert [value_from_unit(uni, x) for x in u] == pytest.approx(2.0 + 4.0 * u)
    lg = parse_sampler("a", {"dist": "loguniform", "low": 1.0, "high": 100.0})
    assert [value_from_unit(lg, x) for x in u] == pytest.approx(10.0 ** (2.0 * u))
    nrm = parse_sampler("a", {"dist": "normal", "mean": 1.0, "std": 2.0})
    assert value_from_unit(nrm, 0.5) == pytest.approx(1.0)
    assert value_from_unit(nrm, 0.8413447460685429) == pytest.approx(3.0)  # Phi(1) -> mean + std
    assert value_from_unit(parse_sampler("a", {"dist": "integer", "low": 0, "high": 1}), 1.0) == 1


def test_sobol_has_lower_discrepancy_than_random():
    from scipy.stats import qmc

    d = qmc_design("sobol", 3, 256, 7)
    assert d.shape == (256, 3)
    r = np.random.default_rng(7).uniform(size=(256, 3))
    assert qmc.discrepancy(d) < 0.5 * qmc.discrepancy(r)


def test_sampling_option_validated_and_hash_compatible(tiny):
    with pytest.raises(CampaignError, match="sampling"):
        make_plan(tiny(sampling="halton"))
    default, explicit = make_plan(tiny()), make_plan(tiny(sampling="random"))
    assert default.hash == explicit.hash  # "random" is the default and keeps earlier hashes
    assert make_plan(tiny(sampling="sobol")).hash != default.hash
    assert default.run_inputs(2) == explicit.run_inputs(2)


def test_qmc_campaign_runs_end_to_end(tiny, tmp_path):
    from formation_ftc.campaign import LocalExecutor, run_campaign

    raw = tiny(runs=4, sampling="sobol", chunk_size=4)
    outcome = run_campaign(raw, tmp_path / "c", executor=LocalExecutor(workers=1), progress=False)
    df = outcome.results.sort_values("run_id")
    plan = make_plan(raw)
    assert list(df["input:controller.kp"]) == [
        plan.run_inputs(r).values["controller.kp"] for r in range(8)
    ]
    assert (df["status"] == "ok").all()
