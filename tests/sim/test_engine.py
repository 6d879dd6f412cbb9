"""The scan driver: decimation, divergence handling, batching, determinism, float64."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.sim.engine import (
    diagnose_divergence,
    run_fixed_step,
    steps_from_horizon,
    trim_records,
)


def _decay(rate):
    def step(k, x):
        return {"x": x["x"] * (1.0 - rate), "acc": x["acc"] + x["x"][0]}

    return step


def test_decimation_and_accumulated_metric():
    out = jax.jit(
        lambda: run_fixed_step(
            _decay(0.1),
            lambda k, x: {"x": x["x"], "k": k},
            {"x": jnp.ones(2), "acc": jnp.asarray(0.0)},
            100,
            10,
        )
    )()
    assert out["records"]["x"].shape == (11, 2)
    np.testing.assert_array_equal(out["records"]["k"], np.arange(0, 101, 10))
    np.testing.assert_allclose(out["records"]["x"][:, 0], 0.9 ** np.arange(0, 101, 10), rtol=1e-13)
    # accumulator sees every step, not only the recorded ones: sum_{k<100} 0.9^k
    assert float(out["final"]["acc"]) == pytest.approx((1 - 0.9**100) / 0.1, rel=1e-13)
    assert int(out["diverged_step"]) == -1


@pytest.mark.parametrize("fold_every", [1, 2, 5, 10])
def test_fold_receives_every_step_sample_in_order(fold_every):
    # the step emits (k, x); fold gets the samples of fold_every consecutive steps with the first step's
    # index: it checks the indices are contiguous and accumulates what a per-step accumulator would
    def step(k, st):
        return {"x": st["x"] * 0.9, "acc": st["acc"], "bad": st["bad"]}, {"k": k, "x": st["x"][0]}

    def fold(k0, st, samples):
        contiguous = jnp.all(samples["k"] == k0 + jnp.arange(fold_every))
        return {
            **st,
            "acc": st["acc"] + jnp.sum(samples["x"]),
            "bad": st["bad"] + jnp.where(contiguous, 0, 1),
        }

    st0 = {"x": jnp.ones(2), "acc": jnp.asarray(0.0), "bad": jnp.asarray(0)}
    out = jax.jit(
        lambda: run_fixed_step(
            step, lambda k, x: {"x": x["x"]}, st0, 100, 10, fold=fold, fold_every=fold_every
        )
    )()
    assert int(out["final"]["bad"]) == 0
    assert float(out["final"]["acc"]) == pytest.approx((1 - 0.9**100) / 0.1, rel=1e-13)
    np.testing.assert_allclose(out["records"]["x"][:, 0], 0.9 ** np.arange(0, 101, 10), rtol=1e-13)


def test_fold_every_must_divide_the_record_interval():
    with pytest.raises(ValueError, match="fold_every=3 must divide record_every=10"):
        run_fixed_step(
            lambda k, x: (x, x),
            lambda k, x: x,
            jnp.zeros(1),
            100,
            10,
            fold=lambda k, s, y: s,
            fold_every=3,
        )


def test_divergence_is_caught_and_diagnosed():
    def step(k, x):  # blows up at step 37 in spacecraft 2's velocity
        v = x["v"].at[1, 0].set(jnp.where(k == 37, jnp.inf, x["v"][1, 0] + 1.0))
        return {"v": v}

    out = jax.jit(lambda: run_fixed_step(step, lambda k, x: x, {"v": jnp.zeros((3, 2))}, 100, 5))()
    # checked once per record block: the block [35, 40) diverges, the returned state is the one at step 35
    assert int(out["diverged_step"]) == 35
    assert np.all(np.isfinite(out["final"]["v"]))  # frozen at the last finite state
    np.testing.assert_array_equal(out["final"]["v"][1, 0], 35.0)
    recs, n = trim_records(jax.tree_util.tree_map(np.asarray, out["records"]), 35, 5)
    assert n == 8 and recs["v"].shape[0] == 8 and np.all(np.isfinite(recs["v"]))
    # the replay finds the exact step (37) and variable
    info = diagnose_divergence(step, out["last_finite"], 35, 3.5, max_steps=5, dt=0.1)
    assert (
        info.step == 37 and info.variable == "v" and info.spacecraft == 1 and info.index == (1, 0)
    )
    assert "t = 3.7 s" in str(info) and "spacecraft 2" in str(info)


def test_observe_traced_once():
    """One ``observe`` in the program: the initial record is the first point of the record scan (the
    last point only records), and the records are those of the running state up to the divergence."""
    calls = []

    def observe(k, x):
        calls.append(k)
        return {"v": x["v"], "k": k}

    def step(k, x):  # blows up at step 37
        return {"v": x["v"].at[1, 0].set(jnp.where(k == 37, jnp.inf, x["v"][1, 0] + 1.0))}

    out = jax.jit(lambda: run_fixed_step(step, observe, {"v": jnp.zeros((3, 2))}, 100, 5))()
    assert len(calls) == 1
    assert out["records"]["v"].shape == (21, 3, 2)
    np.testing.assert_array_equal(out["records"]["k"], np.arange(0, 101, 5))
    np.testing.assert_array_equal(out["records"]["v"][:8, 1, 0], np.arange(0.0, 36.0, 5.0))
    assert not np.isfinite(out["records"]["v"][8, 1, 0])
    np.testing.assert_array_equal(out["final"]["v"][1, 0], 35.0)


def test_simulate_raises_with_partial_results():
    scn = ftc.load_scenario(
        "cw-pd-fault",
        {"simulation.horizon": 60.0, "controller.kp": 1e9, "sensors.position_noise_std": 0.0},
    )
    with pytest.raises(ftc.SimulationDiverged) as info:
        ftc.simulate(scn)
    err = info.value
    assert err.partial is not None and err.partial.sizes["time"] >= 1
    assert np.all(np.isfinite(err.partial.position.values))
    assert "spacecraft" in str(err) and "variable" in str(err)
    assert err.partial.attrs["diverged"]


#: the 20 s cw-pd-fault run: one structure, so one program, for the single runs of the tests below
#: (the 200 steps of the other short cw-pd-fault runs)
CW_20S = {"simulation.horizon": 20.0}


def test_vmap_batch_equals_single_runs():
    from formation_ftc.api import build_loop
    from formation_ftc.sim.programs import jitted_run

    scn = ftc.load_scenario("cw-pd-fault", CW_20S)
    comp = build_loop(scn)
    seeds = jnp.array([1, 2, 3], dtype=jnp.uint32)
    kps = jnp.array([1.0, 2.0, 3.0])
    batch = jax.tree_util.tree_map(lambda a: jnp.stack([a] * 3), comp)
    batch = dataclasses.replace(
        batch, seed=seeds, controller=dataclasses.replace(batch.controller, kp=kps)
    )
    outs = jax.jit(jax.vmap(type(comp).run))(batch)
    for r in range(3):
        single = dataclasses.replace(
            comp,
            seed=seeds[r],
            controller=dataclasses.replace(comp.controller, kp=kps[r]),
        )
        o = jitted_run(comp)(single)  # the program ftc.simulate runs this structure with
        np.testing.assert_allclose(
            outs["records"]["position"][r], o["records"]["position"], rtol=1e-12, atol=1e-12
        )
        np.testing.assert_allclose(outs["metrics"][0][r], o["metrics"][0], rtol=1e-12)


def test_same_seed_same_numbers_different_seed_differs():
    a = ftc.simulate(ftc.load_scenario("cw-pd-fault", CW_20S))
    b = ftc.simulate(ftc.load_scenario("cw-pd-fault", CW_20S))
    c = ftc.simulate(ftc.load_scenario("cw-pd-fault", {**CW_20S, "simulation.seed": 9}))
    np.testing.assert_array_equal(a.position.values, b.position.values)
    assert not np.array_equal(a.position.values, c.position.values)


def test_sampled_and_continuous_modes_converge_as_dt_shrinks():
    base = {
        "simulation.horizon": 100.0,
        "sensors.position_noise_std": 0.0,
        "sensors.velocity_noise_std": 0.0,
        "plant.process_noise_std": 0.0,
    }
    ref = ftc.simulate(
        ftc.load_scenario(
            "cw-pd-fault", {**base, "simulation.dt": 0.01, "simulation.record_every": 100}
        )
    )
    errs = []
    for dt, rec in ((0.2, 5), (0.1, 10)):
        s = ftc.simulate(
            ftc.load_scenario(
                "cw-pd-fault",
                {
                    **base,
                    "simulation.dt": dt,
                    "simulation.record_every": rec,
                    "controller.mode": "sampled",
                },
            )
        )
        errs.append(float(np.abs(s.position.values - ref.position.values).max()))
    # zero-order hold is first order in dt
    assert errs[1] < errs[0] and errs[0] / errs[1] == pytest.approx(2.0, rel=0.25)


def test_steps_from_horizon_errors():
    assert steps_from_horizon(10.0, 0.01) == 1000
    with pytest.raises(ValueError, match="does not divide"):
        steps_from_horizon(10.0, 0.3)
    with pytest.raises(ValueError, match="record_every"):
        steps_from_horizon(10.0, 0.01, 7)


def test_divergence_names_nested_variables():
    from formation_ftc.core.history import History, history_init

    def step(k, st):
        v = jnp.where(k == 3, jnp.nan, st["ctl"]["hist"].values + 1.0)
        return {"ctl": {"hist": History(v, st["ctl"]["hist"].head, st["ctl"]["hist"].count)}}

    st0 = {"ctl": {"hist": history_init(jnp.zeros(2), 4)}}
    out = jax.jit(lambda: run_fixed_step(step, lambda k, x: {}, st0, 10, 5))()
    info = diagnose_divergence(
        step, out["last_finite"], int(out["diverged_step"]), 0.0, max_steps=5, dt=1.0
    )
    assert info.variable == "ctl.hist.values" and info.step == 3


def test_divergence_under_vmap_keeps_each_runs_last_finite_state():
    """Batched runs: one run blows up at step 37, the other never. The diverged run returns its state at
    the start of the failing block (step 35) and its divergence step; the healthy run is untouched; a
    run-independent state leaf (a clock driven only by a shared parameter) stays unbatched inside the
    program (the snapshot never selects on the running state)."""

    def step_of(p):
        def step(k, x):
            v = x["v"].at[1, 0].set(jnp.where((k == p["bad_step"]), jnp.inf, x["v"][1, 0] + 1.0))
            return {"v": v, "clock": x["clock"] + p["dt"]}

        return step

    def run(p):
        return run_fixed_step(
            step_of(p), lambda k, x: x, {"v": jnp.zeros((3, 2)), "clock": jnp.asarray(0.0)}, 100, 5
        )

    params = {"bad_step": jnp.array([37, 1000]), "dt": jnp.asarray(0.1)}
    in_axes = ({"bad_step": 0, "dt": None},)
    out = jax.jit(jax.vmap(run, in_axes=in_axes))(params)
    np.testing.assert_array_equal(out["diverged_step"], [35, -1])
    np.testing.assert_array_equal(out["final"]["v"][:, 1, 0], [35.0, 100.0])
    np.testing.assert_allclose(out["final"]["clock"], [3.5, 10.0], rtol=1e-12)
    recs, n = trim_records(
        jax.tree_util.tree_map(lambda a: np.asarray(a)[0], out["records"]), 35, 5
    )
    assert n == 8 and np.all(np.isfinite(recs["v"]))
    # inside the program the clock's additions are scalar (unbatched) operations
    jaxpr = jax.make_jaxpr(jax.vmap(run, in_axes=in_axes))(params).jaxpr

    def add_shapes(jx, acc):
        for eqn in jx.eqns:
            if eqn.primitive.name == "add" and eqn.outvars[0].aval.dtype == jnp.float64:
                acc.append(tuple(eqn.outvars[0].aval.shape))
            for val in eqn.params.values():
                for sub in val if isinstance(val, (tuple, list)) else (val,):
                    inner = getattr(sub, "jaxpr", sub)
                    if hasattr(inner, "eqns"):
                        add_shapes(inner, acc)
        return acc

    assert () in add_shapes(jaxpr, [])  # the clock update stays a scalar float64 add
    # (control: with dt batched the clock is batched and no scalar float add remains)
    batched_dt = jax.make_jaxpr(jax.vmap(run))(
        {"bad_step": jnp.array([37, 1000]), "dt": jnp.array([0.1, 0.1])}
    )
    assert () not in add_shapes(batched_dt.jaxpr, [])
