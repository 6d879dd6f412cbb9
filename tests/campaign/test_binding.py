"""Campaigns write sampled fields into the parameter leaves their paths name (campaign.binding).

A field binds when its path names one leaf of the template loop (``slot.field`` ->
``loop.<slot>.<field>``, or one level into a wrapped component: no section renames a field)
and that leaf holds the field's value; a derived leaf (an orbit radius turned into a mean motion, a
design weight turned into a gain) is not bound and the runs are built one by one, with the same
results."""

from __future__ import annotations

import copy

import jax
import numpy as np
import pytest

from formation_ftc import api
from formation_ftc.campaign import make_plan, run_campaign, runner
from formation_ftc.campaign.binding import bind_fields

from .conftest import TINY

RTOL = 1e-12  # batched vs single runs: separately compiled programs (see test_runner.py)


def _template(base: str, **overrides):
    sim = api.load_scenario(base).simulation
    scn = api.load_scenario(
        base, {"simulation.horizon": 2 * sim.record_every * sim.dt, **overrides}
    )
    return scn, api.build_loop(scn)


def _leaf_key(loop, n: int) -> str:
    path, _ = jax.tree_util.tree_flatten_with_path(loop)[0][n]
    return jax.tree_util.keystr(path)


@pytest.mark.parametrize(
    ("base", "overrides", "path", "value", "leaf", "elements"),
    [
        pytest.param("cw-pd-fault", {}, "controller.kp", 2.0, ".controller.kp", [0], id="gain"),
        pytest.param("cw-pd-fault", {}, "plant.mass.1", 120.0, ".plant.mass", [1], id="mass"),
        pytest.param(  # a per-spacecraft field given as one number fills every element
            "cw-pd-fault",
            {"controller.nominal_mass": 110.0},
            "controller.nominal_mass",
            110.0,
            ".controller.nominal_mass",
            [0, 1, 2, 3],
            id="per-spacecraft",
        ),
        pytest.param("cw-pd-fault", {}, "simulation.seed", 1, ".seed", [0], id="seed"),
        pytest.param(  # one level into the wrapped law (AccelerationToForce.law)
            "compose-azizi2009-on-li2020",
            {},
            "controller.lambda0",
            2.0,
            ".controller.law.lambda0",
            [0],
            id="wrapped",
        ),
        pytest.param(  # the d_hat adaptation gain mu_i (the on-board gravitational parameter: orbit_mu)
            "compose-li2020-on-cw",
            {},
            "controller.mu",
            1.0,
            ".controller.mu",
            [0, 1, 2, 3],
            id="declared",
        ),
    ],
)
def test_fields_bind_to_the_leaf_their_path_names(base, overrides, path, value, leaf, elements):
    scn, loop = _template(base, **overrides)
    bindings = bind_fields(loop, {path: value})
    assert bindings is not None
    b = bindings[path]
    assert _leaf_key(loop, b.leaf) == leaf and b.index.tolist() == elements


@pytest.mark.parametrize(
    ("base", "values"),
    [
        pytest.param("cw-pd-fault", {"plant.semi_major_axis": 7000e3}, id="derived-mean-motion"),
        pytest.param(
            "compose-lqr-on-cw", {"controller.max_position_error": 10.0}, id="derived-lqr-gain"
        ),
        pytest.param("cw-pd-fault", {"simulation.horizon": 2.0}, id="structural"),
        pytest.param("cw-pd-fault", {"plant.mass.0": 99.0}, id="not-the-leaf-value"),
        pytest.param("cw-pd-fault", {"plant.mass.9": 100.0}, id="no-such-element"),
        pytest.param(
            "cw-pd-fault", {"plant.mass.0": 100.0, "plant.mass.-4": 100.0}, id="one-element-twice"
        ),
        pytest.param(  # a constant of the law's conditions only: no leaf holds it
            "compose-gui2022-on-li2020", {"controller.mu1": 1e-4}, id="no-leaf"
        ),
    ],
)
def test_fields_without_a_leaf_holding_their_value_are_not_bound(base, values):
    scn, loop = _template(base)
    assert bind_fields(loop, values) is None


def _campaign(sample: dict, runs: int = 3) -> dict:
    raw = copy.deepcopy(TINY)
    raw["campaign"].update(runs=runs, chunk_size=runs, seed=5)
    raw["overrides"] = {"simulation.horizon": 20.0}  # the 200 steps of the other tiny campaigns
    raw["sample"] = sample
    raw["traces"] = {"runs": [], "every": 1}
    return raw


def _bound(plan) -> list:
    return [v for k, v in runner._BINDINGS.items() if k[0] == plan.hash]


def test_bound_path_equals_per_run_builds_to_the_bit(tmp_path, monkeypatch):
    raw = _campaign(
        {
            "controller.kp": {"dist": "uniform", "low": 1.0, "high": 3.0},
            "plant.mass.0": {"dist": "uniform", "low": 90.0, "high": 110.0},
            "controller.nominal_mass": {"dist": "uniform", "low": 95.0, "high": 115.0},
            "sensors.position_noise_std": {"dist": "uniform", "low": 0.005, "high": 0.02},
        }
    )
    runner.clear_bindings()
    bound = run_campaign(raw, tmp_path / "bound").results
    entries = _bound(make_plan(raw))
    assert entries and all(e is not None for e in entries)  # the fast path was taken
    assert set(entries[0][1]) == {*raw["sample"], "simulation.seed"}
    monkeypatch.setattr(runner, "_bound_chunk", lambda *a: None)  # one build per run
    built = run_campaign(raw, tmp_path / "built").results
    metrics = [c for c in bound.columns if c.startswith("metric:")]
    assert (bound["status"] == "ok").all() and len(set(bound["metric:delta_v_total"])) == 3
    np.testing.assert_array_equal(bound[metrics].to_numpy(), built[metrics].to_numpy())


def test_a_derived_field_falls_back_to_one_build_per_run(tmp_path):
    raw = _campaign({"plant.semi_major_axis": {"dist": "uniform", "low": 6900e3, "high": 7100e3}})
    runner.clear_bindings()
    df = run_campaign(raw, tmp_path / "derived").results
    plan = make_plan(raw)
    assert _bound(plan) == [None]  # not bound: every run built on its own
    for r in range(plan.n_runs):
        _, single = api.simulate_with_metrics(plan.scenario(plan.run_inputs(r)))
        for name in raw["campaign"]["metrics"]:
            assert df.loc[r, f"metric:{name}"] == pytest.approx(single[name], rel=RTOL)
    assert len(set(df["metric:delta_v_total"])) == 3  # the orbit radius reaches the runs
