"""A campaign that samples a true mass moves the plant, never the law's stated nominal mass (issue
35 item 2: flight knowledge is stated, never copied from truth).

The parameter batch is assembled as the campaign runner's fast path assembles it (one template, the
sampled field written into the leaf its path names,
:func:`~formation_ftc.campaign.binding.apply_bindings`), and every run is also built the slow way
(one validated scenario per run)."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from formation_ftc import api
from formation_ftc.campaign.binding import apply_bindings, bind_fields, take_run
from formation_ftc.campaign.runner import make_plan

from .conftest import TINY

CASES = [
    # base scenario, sampled true-mass field, (plant leaf, flight leaf) holding it / the stated value
    pytest.param(
        "cw-pd-fault",
        "plant.mass.0",
        ("plant", "mass"),
        ("controller", "nominal_mass"),
        100.0,
        id="cw-pd",
    ),
    pytest.param(
        "compose-lqr-on-cw",
        "plant.mass.1",
        ("plant", "mass"),
        ("controller", "nominal_mass"),
        120.0,
        id="lqr",
    ),
    pytest.param(
        "compose-li2020-delays-on-yang2013",
        "plant.mass.2",
        ("plant", "mass"),
        ("controller", "law", "nominal_mass"),
        150.0,
        id="yang2013-law",
    ),
]


def _leaf(loop, path):
    for name in path:
        loop = getattr(loop, name)
    return loop


@pytest.mark.parametrize(("base", "field", "plant_leaf", "flight_leaf", "stated"), CASES)
def test_sampled_true_mass_leaves_the_nominal_mass_unchanged(
    base, field, plant_leaf, flight_leaf, stated
):
    raw = copy.deepcopy(TINY)
    raw["campaign"].update(base=base, runs=4, chunk_size=4)
    raw["campaign"].pop("metrics")
    sim = api.load_scenario(base).simulation
    raw["overrides"] = {
        "simulation.horizon": 2 * sim.record_every * sim.dt
    }  # nothing runs: a valid horizon
    raw["sample"] = {
        field: {
            "dist": "normal",
            "mean": stated,
            "std": 5.0,
            "low": stated - 20.0,
            "high": stated + 20.0,
        }
    }
    raw.pop("traces")
    plan = make_plan(raw)
    runs = list(range(plan.n_runs))
    inputs = [plan.run_inputs(r) for r in runs]
    sampled = np.array([inp.values[field] for inp in inputs], dtype=float)
    assert np.unique(sampled).size == len(runs)  # the true mass really varies

    # the runner's fast path: the sampled field written into the leaf its path names, per run
    scenario = plan.scenario(inputs[0])
    template = api.build_loop(scenario)
    bindings = bind_fields(template, {field: inputs[0].values[field]})
    assert bindings is not None, f"{field} should bind to its parameter leaf"
    batch, axes = apply_bindings(template, bindings, {field: sampled}, len(runs))
    index = int(field.rsplit(".", 1)[1]) if field[-1].isdigit() else 0
    # the plant's true mass is batched and follows the samples ...
    assert _leaf(axes, plant_leaf) == 0
    np.testing.assert_array_equal(np.asarray(_leaf(batch, plant_leaf))[:, index], sampled)
    # ... the law's nominal mass is not batched: one stated value for every run
    assert _leaf(axes, flight_leaf) is None
    nominal = np.asarray(_leaf(template, flight_leaf))
    assert nominal[index] == stated
    # the slow path agrees: every run built from its own validated scenario
    for r, inp in zip(runs, inputs, strict=True):
        loop = api.build_loop(plan.scenario(inp))
        np.testing.assert_array_equal(np.asarray(_leaf(loop, flight_leaf)), nominal)
        assert np.asarray(_leaf(loop, plant_leaf))[index] == sampled[r]
        np.testing.assert_array_equal(
            np.asarray(_leaf(take_run(batch, axes, r), flight_leaf)), nominal
        )
