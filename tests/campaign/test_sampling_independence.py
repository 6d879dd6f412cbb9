"""Sampled fields draw independent streams: two fields with the same distribution are uncorrelated over
400 runs (|r| < 0.2; under independence |r| has standard deviation 1/sqrt(400) = 0.05), and no two
fields share their values. Fails when the field path is dropped from the stream key."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from formation_ftc.campaign import make_plan

FIELDS = ("plant.mass.0", "plant.mass.1", "controller.kp")


def _raw(paired: bool, sampling: str | None):
    camp = {
        "name": "indep",
        "base": "cw-pd-fault",
        "runs": 400,
        "seed": 5,
        "chunk_size": 100,
        "paired": paired,
        "metrics": ["max_position_error"],
    }
    if sampling:
        camp["sampling"] = sampling
    return {
        "campaign": camp,
        "overrides": {"simulation.horizon": 20.0},
        "sample": {f: {"dist": "uniform", "low": 1.0, "high": 2.0} for f in FIELDS},
    }


@pytest.mark.parametrize(("paired", "sampling"), [(False, None), (True, None), (False, "lhs")])
def test_same_distribution_fields_are_uncorrelated(paired, sampling):
    plan = make_plan(_raw(paired, sampling))
    vals = np.array([[plan.run_inputs(r).values[f] for f in FIELDS] for r in range(400)])
    assert np.all((vals >= 1.0) & (vals <= 2.0))
    for a, b in itertools.combinations(range(len(FIELDS)), 2):
        assert not np.array_equal(vals[:, a], vals[:, b])
        r = np.corrcoef(vals[:, a], vals[:, b])[0, 1]
        assert abs(r) < 0.2, (FIELDS[a], FIELDS[b], r)
