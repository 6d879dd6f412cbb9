"""Evaluation ``chain-errors`` and the threshold flag: against their formulas; a listed chain-errors
replaces the one the law adds, and its metric set counts the supervisor's metrics only with it."""

from __future__ import annotations

import copy

import jax.numpy as jnp
import numpy as np

from formation_ftc.api import load_scenario
from formation_ftc.components.evaluations.chain_errors import ChainTrackingError
from formation_ftc.components.supervisors.hierarchical import ThresholdFlag
from formation_ftc.config import loader
from formation_ftc.methods.composed import make_loop


def test_tracking_error_and_threshold_flag_against_their_formulas():
    # (x_j - x_i) - (x_j^d - x_i^d)
    pos, des = np.arange(12.0).reshape(4, 3) ** 2, np.arange(12.0).reshape(4, 3)
    te = ChainTrackingError().outputs(
        {"position": jnp.asarray(pos), "desired_position": jnp.asarray(des)}
    )
    np.testing.assert_allclose(te["tracking_error"], (pos[1:] - pos[:-1]) - (des[1:] - des[:-1]))
    flag = ThresholdFlag(name="f", source="s", threshold=jnp.asarray(0.25))
    assert [bool(flag.outputs({"s": jnp.asarray(v)})["f"]) for v in (0.2, 0.25, 0.3)] == [
        False,
        True,
        True,
    ]


def _loop(drop=()):
    raw = copy.deepcopy(loader.read_raw("azizi2009-flfr")[0])
    raw["simulation"]["horizon"] = 2.0
    for slot in drop:
        raw.pop(slot)
    return make_loop(load_scenario(raw))


def test_the_listed_chain_errors_replace_the_law_s_and_count_the_supervisor_s_metrics():
    """azizi2009-flfr lists chain-errors with the paper's metrics: one ChainTrackingError (after the
    supervisor's flag), and t_flfr / n_events because the HL supervisor records its modes."""
    loop = _loop()
    assert [type(e).__name__ for e in loop.evaluations] == ["ThresholdFlag", "ChainTrackingError"]
    names = {m.name for m in loop.metrics}
    assert {"max_err", "max_err_x", "t_flfr", "n_events", "max_err_after_flfr"} <= names


def test_without_the_supervisor_no_supervisor_metrics():
    loop = _loop(drop=("supervisor",))
    names = {m.name for m in loop.metrics}
    assert [type(e).__name__ for e in loop.evaluations] == ["ChainTrackingError"]
    assert {"max_err", "max_err_x"} <= names
    assert not {"t_flfr", "n_events", "max_err_after_flfr"} & names


def test_the_law_adds_the_chain_errors_where_none_is_listed():
    loop = _loop(drop=("evaluations",))
    assert [type(e).__name__ for e in loop.evaluations] == ["ThresholdFlag", "ChainTrackingError"]
    assert not loop.metrics
