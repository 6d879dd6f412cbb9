"""A reproduction's runs (formation_ftc.papers.programs): a second scenario of the same structure
compiles nothing and gives bit-for-bit the results of a program compiled afresh for it; batches of one
structure equal the runs alone. (The shared program itself: tests/sim/test_programs.py.)

Truths: a fresh ``jax.jit`` of the scenario's own ``run`` with the same XLA options, and JAX's own
compile events (``jax.monitoring``, the ``run_compiles`` fixture of tests/conftest.py).
"""

from __future__ import annotations

import jax
import numpy as np

from formation_ftc.api import build_loop, finish_run, load_scenario
from formation_ftc.papers import programs
from formation_ftc.sim.runtime import xla


def test_same_structure_compiles_once_and_matches_the_api(cw_gain_pair, run_compiles):
    a, b = cw_gain_pair
    assert build_loop(a).static_key == build_loop(b).static_key
    programs.clear()
    jax.clear_caches()  # JAX's caches keyed by the jitted function outlive programs.clear()
    run_compiles.clear()
    ds_a, m_a = programs.simulate(a)
    n_first = len(run_compiles)
    ds_b, m_b = programs.simulate(b)
    assert n_first == 1 and len(run_compiles) == 1  # the second scenario reused the program
    assert m_a != m_b  # the gains differ, so do the results
    for scn, ds, m in ((a, ds_a, m_a), (b, ds_b, m_b)):
        c = build_loop(scn)

        def run(p):  # a program of its own (a new function; named as the shared ones)
            return p.run()

        ref_ds, ref_m = finish_run(scn, c, xla.jit(run)(c))
        assert m == ref_m  # bit for bit
        for name in ref_ds.data_vars:
            np.testing.assert_array_equal(ds[name].values, ref_ds[name].values)
    assert len(run_compiles) == 3  # each fresh program was compiled


def test_simulate_batched_groups_by_structure_and_keeps_the_order():
    """Two structures in one call (two gain sets of the new ILO, and the ILO of [25]): one batch each,
    results in the callers' order and equal to the runs alone through :func:`programs.simulate`
    (separately compiled programs: same arithmetic per element, so 1e-12 relative)."""
    h = {"simulation.horizon": 2.0}
    scns = [
        load_scenario("gui2022-ilo", h),
        load_scenario("gui2022-ilo-baseline", h),
        load_scenario("gui2022-ilo", {**h, "estimator.gains": "lmi"}),
    ]
    timings: list = []
    batched = programs.simulate_batched(scns, timings=timings)
    assert len(batched) == len(timings) == 3
    assert timings[0] == timings[2] != timings[1]  # runs 0 and 2 share one batch
    for scn, (ds_b, m_b) in zip(scns, batched, strict=True):
        ds_1, m_1 = programs.simulate(scn)
        assert ds_b.attrs["scenario_name"] == scn.scenario.name and m_b.keys() == m_1.keys()
        for k in m_1:
            np.testing.assert_allclose(m_b[k], m_1[k], rtol=1e-12, atol=1e-300, err_msg=k)
