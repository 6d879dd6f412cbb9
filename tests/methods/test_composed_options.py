"""Composition options added for the league: explicit formation offsets, Gui2022 laws holding fixed slots,
``[[evaluations]]`` sections, metrics naming unrecorded signals, and divergence replays compiled once per
loop structure."""

from __future__ import annotations

import copy
import tomllib

import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.api import build_loop, simulate_with_metrics
from formation_ftc.core.dynamics.cw import cw_free_motion
from formation_ftc.methods.composed import make_loop
from formation_ftc.scenarios import __path__ as SCENARIOS

RAW = tomllib.loads(open(f"{SCENARIOS[0]}/compose-li2020-on-cw.toml").read())
GUI = tomllib.loads(open(f"{SCENARIOS[0]}/compose-gui2022-on-li2020.toml").read())
SLOTS = [[100.0, 100.0, 0.0], [-100.0, 100.0, 0.0], [-100.0, -100.0, 0.0], [100.0, -100.0, 0.0]]


def _raw(base=RAW, **edits):
    raw = copy.deepcopy(base)
    raw["simulation"]["horizon"] = 5.0
    for path, value in edits.items():
        node = raw
        *head, last = path.split("__")
        for p in head:
            node = node.setdefault(p, {})
        node[last] = value
    return raw


def test_explicit_formation_offsets_are_the_desired_positions():
    loop = make_loop(
        ftc.load_scenario(_raw(controller__formation={"offsets": SLOTS, "period": 5800.0}))
    )
    np.testing.assert_array_equal(np.asarray(loop.controller.formation.offsets), SLOTS)
    out = loop.controller.formation.at(
        np.asarray(123.0)
    )  # no rotation, growth or centre motion: fixed
    np.testing.assert_allclose(np.asarray(out["rho_d"]), SLOTS, atol=1e-12)
    np.testing.assert_allclose(np.asarray(out["v_d"]), 0.0, atol=1e-12)
    for bad in (
        {"offsets": SLOTS, "radius": 5.0, "phase": [0, 1, 2, 3], "period": 5800.0},
        {"period": 5800.0},
        {"offsets": SLOTS[:3], "period": 5800.0},
    ):
        with pytest.raises(ValueError, match="formation"):
            ftc.load_scenario(_raw(controller__formation=bad))


def test_gui2022_laws_hold_fixed_slots_or_follow_free_cw_motion():
    desired = [row + [0.0, 0.0, 0.0] for row in SLOTS]
    held = make_loop(
        ftc.load_scenario(
            _raw(GUI, controller__desired_state=desired, controller__desired_motion="hold")
        )
    ).controller
    free = make_loop(ftc.load_scenario(_raw(GUI, controller__desired_state=desired))).controller
    law_h, law_f = getattr(held, "law", held), getattr(free, "law", free)
    t = np.asarray(500.0)
    np.testing.assert_allclose(np.asarray(law_h.exogenous(t)["q0"]), desired, atol=1e-12)
    n = float(law_f.mean_motion)
    np.testing.assert_allclose(
        np.asarray(law_f.exogenous(t)["q0"]),
        np.asarray(cw_free_motion(n, np.asarray(desired), t)),
        rtol=1e-12,
        atol=1e-9,
    )
    # a radial offset is not free motion: the natural reference leaves the slot
    assert np.abs(np.asarray(law_f.exogenous(t)["q0"])[:, :3] - np.asarray(SLOTS)).max() > 1.0
    with pytest.raises(ValueError, match="desired_motion"):
        ftc.load_scenario(_raw(GUI, controller__desired_motion="frozen"))


def test_evaluation_sections_are_validated_and_recorded():
    ds, m = simulate_with_metrics(
        ftc.load_scenario(
            _raw(
                evaluations=[{"type": "formation-scores", "desired": SLOTS}],
                metrics=[{"name": "shape", "signal": "shape_error", "reduce": "max"}],
            )
        )
    )
    rho = ds["position"].values
    ref = max(
        np.linalg.norm((rho[:, i] - rho[:, j]) - (np.subtract(SLOTS[i], SLOTS[j])), axis=-1).max()
        for i in range(4)
        for j in range(i + 1, 4)
    )
    assert m["shape"] >= ref - 1e-9  # every step counts in the metric, the records are a subset
    with pytest.raises(ValueError, match=r"evaluations\[0\]\.type = 'nope'"):
        ftc.load_scenario(_raw(evaluations=[{"type": "nope"}]))
    with pytest.raises(ValueError, match=r"evaluations\[0\]\.desired"):
        ftc.load_scenario(_raw(evaluations=[{"type": "formation-scores"}]))
    with pytest.raises(ValueError, match="3 slots for 4 spacecraft"):
        ftc.load_scenario(_raw(evaluations=[{"type": "formation-scores", "desired": SLOTS[:3]}]))


def test_a_metric_of_an_unrecorded_signal_is_rejected_naming_it():
    with pytest.raises(ValueError, match="'no_such_signal' is not a recorded signal"):
        ftc.load_scenario(_raw(metrics=[{"name": "x", "signal": "no_such_signal"}]))
    with pytest.raises(ValueError, match="gate 'no_gate'"):
        ftc.load_scenario(
            _raw(metrics=[{"name": "x", "signal": "position_error", "gate": "no_gate"}])
        )


def test_divergence_replays_compile_once_per_structure():
    from formation_ftc.sim import engine

    def diverged(kp):
        sc = ftc.load_scenario("cw-pd-fault", {"simulation.horizon": 60.0, "controller.kp": kp})
        with pytest.raises(Exception, match="diverged"):
            simulate_with_metrics(sc)
        return build_loop(sc)

    steps = engine._jitted(engine._params_step)._cache_size()
    diverged(1e6)
    size = engine._jitted(engine._params_replay)._cache_size()
    assert size >= 1  # the diagnostic went through the compiled replay
    diverged(2e6)  # another run of the same structure: the replay program is reused
    assert engine._jitted(engine._params_replay)._cache_size() == size
    # the replay hands back the first failing state itself: no one-step program is compiled beside it
    assert engine._jitted(engine._params_step)._cache_size() == steps


def test_block_metrics_from_a_scenario_file_need_a_block_and_match_numpy():
    """`block_rms` / `block_dev_rms` are offered in [[metrics]]: a missing block is a validation error
    naming the field; with one, the metric equals numpy on the every-step records."""
    with pytest.raises(ValueError, match="block = 0: reduce = 'block_rms' needs a block"):
        ftc.load_scenario(
            _raw(metrics=[{"name": "x", "signal": "position_error", "reduce": "block_rms"}])
        )
    raw = _raw(
        metrics=[
            {
                "name": "lp",
                "signal": "position_error",
                "reduce": "block_rms",
                "block": 5,
                "norm": True,
                "spacecraft": "max",
            },
            {
                "name": "hf",
                "signal": "position_error",
                "reduce": "block_dev_rms",
                "block": 5,
                "norm": True,
                "spacecraft": "max",
            },
        ]
    )
    raw["simulation"]["record_every"] = 1
    ds, metrics = simulate_with_metrics(ftc.load_scenario(raw))
    # spacecraft combined first (max over spacecraft at each step), the horizon sample excluded
    e = np.linalg.norm(ds.position_error.values, axis=-1).max(axis=1)[:-1]
    n_blocks = e.shape[0] // 5
    blocks = e[: n_blocks * 5].reshape(n_blocks, 5)
    lp = np.sqrt(np.mean(blocks.mean(axis=1) ** 2))
    hf = np.sqrt(np.mean((blocks - blocks.mean(axis=1, keepdims=True)) ** 2))
    assert n_blocks >= 4 and hf > 1e-6 * lp  # a real test: several blocks, a deviation inside them
    np.testing.assert_allclose(metrics["lp"], lp, rtol=1e-12)
    np.testing.assert_allclose(metrics["hf"], hf, rtol=1e-12)
