"""Batching runs with shared parameters (sim/batch.py): stacking rules, equality with single runs,
and the property that makes it fast -- work that depends only on shared parameters is not batched."""

from __future__ import annotations

import dataclasses

import jax
import numpy as np
import pytest
from cachetools import LRUCache

from formation_ftc import api
from formation_ftc.sim import batch as batch_module
from formation_ftc.sim.batch import batched_grid_run, batched_run, stack_params, stack_params_grid
from formation_ftc.sim.components import component, static
from formation_ftc.sim.programs import jitted_run


def test_batch_program_cache_keeps_the_most_recently_used(monkeypatch):
    """The per-process cache of batch programs is bounded (least recently used dropped first), and a
    cached program is returned unchanged on a second call."""
    monkeypatch.setattr(batch_module, "_CACHE", LRUCache(maxsize=2))
    batch_module.clear()

    @component
    class Doubler:
        x: object
        static_key: str = static(default="a")

        def run(self):
            return {"y": 2.0 * self.x}

    def program(key):
        return Doubler(x=np.zeros(3), static_key=key)

    axes = Doubler(x=0, static_key="a")
    a = batched_run(program("a"), axes, 3)
    assert batched_run(program("a"), axes, 3) is a  # cached
    b = batched_run(program("b"), axes, 3)
    assert batched_run(program("a"), axes, 3) is a  # a used last: b is the oldest now
    batched_run(program("c"), axes, 3)  # evicts b
    assert batched_run(program("a"), axes, 3) is a
    assert batched_run(program("b"), axes, 3) is not b  # rebuilt
    np.testing.assert_array_equal(a(Doubler(x=np.arange(3.0)))["y"], [0.0, 2.0, 4.0])
    batch_module.clear()


def test_stack_params_shares_equal_leaves_and_pads():
    p = [
        {"a": np.array([1.0, 2.0]), "b": 3.0, "c": np.array([np.nan])},
        {"a": np.array([1.0, 2.5]), "b": 3.0, "c": np.array([np.nan])},
    ]
    batch, axes = stack_params(p, size=4)
    assert axes == {"a": 0, "b": None, "c": None}
    assert batch["a"].shape == (4, 2) and np.array_equal(
        batch["a"][3], [1.0, 2.5]
    )  # padded with the last
    assert batch["b"] == 3.0 and batch["c"].shape == (1,)  # NaN == NaN: shared
    with pytest.raises(ValueError, match="size = 1 < number of runs 2"):
        stack_params(p, size=1)
    with pytest.raises(ValueError, match="different parameter structure"):
        stack_params([{"a": 1.0}, {"b": 1.0}])
    with pytest.raises(ValueError, match="no runs"):
        stack_params([])


def _jaxpr_ops(jaxpr, names, found, loops_only=False, in_loop=False):
    """(primitive, output shape) of every equation named in ``names``, nested jaxprs included
    (``loops_only``: only those inside a scan / while body, i.e. evaluated at every step)."""
    for eqn in jaxpr.eqns:
        if eqn.primitive.name in names and (in_loop or not loops_only):
            found.append((eqn.primitive.name, tuple(eqn.outvars[0].aval.shape)))
        for v in eqn.params.values():
            subs = v if isinstance(v, (tuple, list)) else (v,)
            for sub in subs:
                inner = getattr(sub, "jaxpr", sub)
                if hasattr(inner, "eqns"):
                    _jaxpr_ops(
                        inner,
                        names,
                        found,
                        loops_only,
                        in_loop or eqn.primitive.name in ("scan", "while"),
                    )
    return found


@pytest.fixture(scope="module")
def li2020_runs():
    scn = api.load_scenario(
        "li2020-thm1", {"simulation.horizon": 2.0, "simulation.record_every": 50}
    )
    c = api.build_loop(scn)
    masses = (1.0, 1.07, 0.93)
    params = [
        dataclasses.replace(c, plant=dataclasses.replace(c.plant, mass=c.plant.mass * m))
        for m in masses
    ]
    return c, params


def test_shared_batch_equals_single_and_fully_stacked_runs(li2020_runs):
    """The same runs three ways: batched with shared leaves, every leaf stacked, one by one (jit).
    Separate XLA programs round differently only in the last bits (1e-12 relative on positions)."""
    c, params = li2020_runs
    batch, axes = stack_params(params)
    assert axes.plant.mass == 0 and axes.reference.semi_latus_rectum is None
    assert axes.controller.formation.offsets is None
    shared = batched_run(c, axes, len(params))(batch)
    full = jax.jit(jax.vmap(type(c).run))(jax.tree_util.tree_map(lambda *x: np.stack(x), *params))
    single = jax.jit(type(c).run)
    for k, p in enumerate(params):
        ref = np.asarray(single(p)["final"]["plant"]["q"])[:, :3]  # positions
        np.testing.assert_allclose(
            shared["final"]["plant"]["q"][k][:, :3], ref, rtol=1e-12, atol=1e-12
        )
        np.testing.assert_allclose(
            full["final"]["plant"]["q"][k][:, :3], ref, rtol=1e-12, atol=1e-12
        )
        np.testing.assert_allclose(
            shared["records"]["mu1"][k],
            np.asarray(single(p)["records"]["mu1"]),
            rtol=1e-12,
            atol=1e-12,
        )
    assert shared["final"]["reference"].shape == (3,)  # outputs are broadcast to the run axis


def test_run_independent_work_is_not_batched(li2020_runs):
    """Structural performance guard (no timing): with the orbit and formation shared, every sin/cos
    of the batched Li2020 program (reference true anomaly, desired-formation rotation) acts on
    run-independent values; none is evaluated per run at any step. This is what the engine's divergence
    snapshot (no select on the running state) and the reference orbit's stage values computed once per
    step (ClosedLoop's reference slot) preserve. (The observation of the final, per-run last-finite
    state, once after the loop, may evaluate the orbit per run.)"""
    c, params = li2020_runs
    B = 7
    batch, axes = stack_params(params + [params[-1]] * (B - len(params)))
    jaxpr = jax.make_jaxpr(jax.vmap(type(c).run, in_axes=(axes,)))(batch).jaxpr
    trig = _jaxpr_ops(jaxpr, {"sin", "cos"}, [], loops_only=True)
    assert trig, "expected the orbit/formation trigonometry in the program"
    batched = [(n, s) for n, s in trig if B in s]
    assert not batched, f"trigonometry evaluated per run: {batched}"


def test_stack_params_grid_stores_each_leaf_by_what_it_depends_on():
    def run(r, c):
        return {
            "shared": np.array([1.0, 2.0]),
            "row": np.array([10.0 * r]),
            "col": float(c),
            "cell": np.array([r, c], dtype=float),
            "nan": np.array([np.nan]),
        }

    grid = [[run(r, c) for c in range(3)] for r in range(2)]
    batch, row_axes, col_axes = stack_params_grid(grid)
    assert (row_axes, col_axes) == (
        {"shared": None, "row": 0, "col": None, "cell": 0, "nan": None},
        {"shared": None, "row": None, "col": 0, "cell": 0, "nan": None},
    )
    assert (
        batch["shared"].shape == (2,)
        and batch["row"].shape == (2, 1)
        and batch["col"].shape == (3,)
    )
    assert batch["cell"].shape == (2, 3, 2) and batch["nan"].shape == (1,)
    np.testing.assert_array_equal(batch["row"][:, 0], [0.0, 10.0])
    np.testing.assert_array_equal(batch["col"], [0.0, 1.0, 2.0])
    np.testing.assert_array_equal(batch["cell"][1, 2], [1.0, 2.0])
    with pytest.raises(ValueError, match="row 1 has 2 runs, row 0 has 3"):
        stack_params_grid([grid[0], grid[1][:2]])
    with pytest.raises(ValueError, match=r"run \(1, 0\) has a different parameter structure"):
        stack_params_grid([grid[0], [{"x": 1.0}] + grid[1][1:]])
    with pytest.raises(ValueError, match="no runs"):
        stack_params_grid([])


def test_grid_batch_equals_single_runs_and_draws_each_rows_noise_once():
    """A grid of noisy runs, seeds (rows) x gains (columns): every cell equals the run alone (a program
    of its own; 1e-12 relative, the programs are compiled separately), and every random draw in the
    step acts on the seeds only -- its shapes lead with the row count and never carry the column count."""
    R, C = 5, 7  # neither is a dimension of the cw-pd-fault noise (4 spacecraft x 3 axes)
    h = {"simulation.horizon": 20.0}
    scns = [
        [
            api.load_scenario(
                "cw-pd-fault", {**h, "simulation.seed": 11 + r, "controller.kp": 1.0 + 0.25 * c}
            )
            for c in range(C)
        ]
        for r in range(R)
    ]
    compiled = [[api.build_loop(s) for s in row] for row in scns]
    c0 = compiled[0][0]
    batch, row_axes, col_axes = stack_params_grid([[c for c in row] for row in compiled])
    assert row_axes.seed == 0 and col_axes.seed is None  # the seed is a row leaf
    out = jax.device_get(batched_grid_run(c0, row_axes, col_axes, R, C)(batch))
    assert np.shape(out["metrics"][0])[:2] == (R, C)
    for r in range(R):
        for c in range(C):
            alone = jax.device_get(
                jitted_run(compiled[r][c])(compiled[r][c])
            )  # one program, unbatched
            for k, (a, b) in enumerate(zip(out["metrics"], alone["metrics"], strict=True)):
                np.testing.assert_allclose(
                    np.asarray(a)[r, c], b, rtol=1e-12, atol=1e-300, err_msg=f"({r},{c}) {k}"
                )
    inner = jax.vmap(type(c0).run, in_axes=(col_axes,), axis_size=C)
    jaxpr = jax.make_jaxpr(jax.vmap(inner, in_axes=(row_axes,), axis_size=R))(batch).jaxpr
    draws = _jaxpr_ops(jaxpr, {"random_bits", "erf_inv"}, [], loops_only=True)
    assert draws, "expected random draws in the step"
    assert all(shape[:1] == (R,) and C not in shape for _, shape in draws), (
        draws
    )  # (R, 4, 3), not (R, C, ...)
