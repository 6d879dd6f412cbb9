"""Run inputs are a pure function of (campaign seed, run id): determinism, subset and order
invariance, chunk layout, and the distributions themselves (checked against their closed forms)."""

from __future__ import annotations

import random

import numpy as np
import pytest
from scipy import stats

from formation_ftc.campaign import make_plan
from formation_ftc.campaign.sampling import draw_value, run_seed
from formation_ftc.campaign.spec import parse_sampler


def test_same_plan_same_inputs_any_order(tiny):
    a, b = make_plan(tiny(runs=7)), make_plan(tiny(runs=7))
    ids = list(range(a.n_runs))
    forward = [a.run_inputs(r) for r in ids]
    random.Random(3).shuffle(ids)
    shuffled = {r: b.run_inputs(r) for r in ids}
    assert all(shuffled[x.run_id] == x for x in forward)
    # every input column is set and the scenario seed equals the run's derived seed
    scn = a.scenario(forward[5])
    assert scn.simulation.seed == forward[5].seed
    assert scn.section("controller").kp == forward[5].values["controller.kp"]
    assert scn.section("controller").kd == forward[5].values["controller.kd"]
    assert scn.section("plant").mass[0] == forward[5].values["plant.mass.0"]
    assert scn.simulation.horizon == 20.0  # the campaign's fixed override


def test_subset_is_independent_of_campaign_size_and_chunking(tiny):
    small, big = make_plan(tiny(runs=3, chunk_size=2)), make_plan(tiny(runs=50, chunk_size=7))
    # replicate j of grid point g is run g*runs + j in each plan; its inputs do not depend on runs/chunks
    for g in range(2):
        for j in range(3):
            x, y = small.run_inputs(g * 3 + j), big.run_inputs(g * 50 + j)
            assert (x.seed, x.values, x.grid_index, x.replicate) == (
                y.seed,
                y.values,
                y.grid_index,
                y.replicate,
            )


def test_a_later_block_of_replicates_runs_those_replicates(tiny):
    """first_replicate = s: replicate j is replicate s + j of the whole stream (seed, samples and the
    replicate column), per run and per column; a quasi-Monte Carlo design refuses it."""
    whole, block = make_plan(tiny(runs=9)), make_plan(tiny(runs=4, first_replicate=5))
    for g in range(2):
        for j in range(4):
            x, y = whole.run_inputs(g * 9 + 5 + j), block.run_inputs(g * 4 + j)
            assert (x.seed, x.values, x.replicate) == (y.seed, y.values, y.replicate)
    cols = block.run_columns(list(range(block.n_runs)))
    assert cols.replicate.tolist() == [5, 6, 7, 8] * 2
    assert cols.seed.tolist() == [
        whole.run_inputs(g * 9 + j).seed for g in (0, 1) for j in range(5, 9)
    ]
    with pytest.raises(Exception, match="first_replicate"):
        make_plan(tiny(runs=4, first_replicate=5, sampling="sobol"))


def test_paired_common_random_numbers_and_unpaired(tiny):
    p = make_plan(tiny(runs=4))
    a, b = p.run_inputs(1), p.run_inputs(4 + 1)  # replicate 1 at kd = 10 and kd = 30
    assert a.values["controller.kd"] == 10.0 and b.values["controller.kd"] == 30.0
    assert a.seed == b.seed and a.values["controller.kp"] == b.values["controller.kp"]
    q = make_plan(tiny(runs=4, paired=False))
    c, d = q.run_inputs(1), q.run_inputs(5)
    assert c.seed != d.seed and c.values["controller.kp"] != d.values["controller.kp"]
    assert q.run_inputs(1).seed == run_seed(11, 1) and q.run_inputs(5).seed == run_seed(11, 5)
    # the campaign seed matters
    assert make_plan(tiny(runs=4, seed=12)).run_inputs(1).seed != a.seed


def test_adding_a_sampled_field_keeps_the_others(tiny):
    raw = tiny(runs=5)
    p1 = make_plan(raw)
    raw["sample"]["sensors.position_noise_std"] = {"dist": "uniform", "low": 1.0, "high": 2.0}
    p2 = make_plan(raw)
    for r in range(p1.n_runs):
        v1, v2 = p1.run_inputs(r).values, p2.run_inputs(r).values
        assert all(v2[k] == v for k, v in v1.items())
        assert 1.0 <= v2["sensors.position_noise_std"] <= 2.0
    assert p1.hash != p2.hash


def test_chunks_cover_every_run_once_within_grid_points(tiny):
    p = make_plan(tiny(runs=5, chunk_size=2))
    chunks = p.chunks()
    assert [c.chunk_id for c in chunks] == list(range(p.n_chunks)) == list(range(6))
    runs = [r for c in chunks for r in c.run_ids]
    assert runs == list(range(10))
    for c in chunks:
        assert {p.run_inputs(r).grid_index for r in c.run_ids} == {c.grid_index}
        assert p.chunk(c.chunk_id) == c
    assert [len(c) for c in chunks] == [2, 2, 1, 2, 2, 1]


def test_multiple_bases_are_a_grid_axis(tiny, tmp_path):
    from formation_ftc.config.loader import builtin_scenarios

    other = tmp_path / "cw-other.toml"
    other.write_text(
        builtin_scenarios()["cw-pd-fault"].replace('name = "cw-pd-fault"', 'name = "cw-other"')
    )
    raw = tiny(runs=2, base=["cw-pd-fault", "missing.toml"])
    raw["traces"]["runs"] = [0]
    with pytest.raises(Exception, match="does not exist"):
        make_plan(raw)
    raw["campaign"]["base"] = ["cw-pd-fault", str(other)]
    p = make_plan(raw)
    assert p.n_grid == 4 and p.n_runs == 8 and p.swept() == ["scenario", "input:controller.kd"]
    bases = [p.run_inputs(r).base for r in range(8)]
    assert bases == ["cw-pd-fault"] * 4 + [str(other)] * 4  # base is the outermost grid axis
    assert p.scenario(p.run_inputs(5)).scenario.name == "cw-other"
    # paired: replicate 1 has the same sampled kp on both bases
    assert p.run_inputs(1).values["controller.kp"] == p.run_inputs(5).values["controller.kp"]


N = 4000  # draws per distribution test; tolerances below are 5 standard errors


def _draws(spec):
    s = parse_sampler("x", spec)
    return np.array([draw_value(s, 99, k) for k in range(N)])


def test_uniform_and_loguniform_match_closed_form():
    u = _draws({"dist": "uniform", "low": 2.0, "high": 5.0})
    assert u.min() >= 2.0 and u.max() < 5.0
    assert abs(u.mean() - 3.5) < 5 * 3 / np.sqrt(12 * N)
    assert stats.kstest(u, stats.uniform(2.0, 3.0).cdf).pvalue > 1e-4
    lu = np.log(_draws({"dist": "loguniform", "low": 0.1, "high": 10.0}))
    assert stats.kstest(lu, stats.uniform(np.log(0.1), np.log(100.0)).cdf).pvalue > 1e-4


def test_normal_and_truncated_normal_match_closed_form():
    x = _draws({"dist": "normal", "mean": 1.0, "std": 2.0})
    assert stats.kstest(x, stats.norm(1.0, 2.0).cdf).pvalue > 1e-4
    t = _draws({"dist": "normal", "mean": 1.0, "std": 2.0, "low": 0.0, "high": 2.0})
    assert t.min() >= 0.0 and t.max() <= 2.0
    assert stats.kstest(t, stats.truncnorm(-0.5, 0.5, loc=1.0, scale=2.0).cdf).pvalue > 1e-4


def test_integer_and_weighted_choice_frequencies():
    k = _draws({"dist": "integer", "low": -1, "high": 2})
    assert set(k.tolist()) == {-1, 0, 1, 2}  # both ends inclusive
    for v in (-1, 0, 1, 2):
        assert abs(np.mean(k == v) - 0.25) < 5 * np.sqrt(0.25 * 0.75 / N)
    s = parse_sampler("x", {"choice": ["a", "b"], "weights": [3.0, 1.0]})
    c = np.array([draw_value(s, 5, j) for j in range(N)])
    assert abs(np.mean(c == "a") - 0.75) < 5 * np.sqrt(0.75 * 0.25 / N)
