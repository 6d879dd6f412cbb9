"""One compiled program per structure, shared by every front end of a process
(formation_ftc.sim.programs): a second run of a structure -- another gain -- is neither traced nor
compiled again, and gives bit for bit the results of a program compiled afresh for it.

Truths: a fresh ``jax.jit`` of the scenario's own ``run`` with the same XLA options (compiled anew,
independent of the shared cache); JAX's compile events (``jax.monitoring``, the ``run_compiles``
fixture of tests/conftest.py);
a count of the traces of the closed loop (``ClosedLoop._run`` is called once per trace, never per step).
"""

from __future__ import annotations

import jax
import numpy as np
import pytest
from cachetools import LRUCache

from formation_ftc.api import build_loop, finish_run, load_scenario, simulate_with_metrics
from formation_ftc.sim import programs
from formation_ftc.sim.loop import ClosedLoop
from formation_ftc.sim.runtime import xla


@pytest.fixture
def traces(monkeypatch):
    """Number of closed-loop traces from here on (JAX's trace caches emptied first: they are keyed by
    the jitted function, which outlives ``programs.clear()``)."""
    jax.clear_caches()
    count = [0]
    run = ClosedLoop._run

    def counted(self):
        count[0] += 1
        return run(self)

    monkeypatch.setattr(ClosedLoop, "_run", counted)
    return count


def _fresh(scenario):
    """The scenario run through a program compiled for it alone (a new ``jax.jit`` of a new function:
    ``jax.jit(ClosedLoop.run)`` would share JAX's trace cache with every other jit of that method)."""
    c = build_loop(scenario)

    def run(p):  # named as the shared programs' function, so run_compiles counts it
        return p.run()

    return finish_run(scenario, c, xla.jit(run)(c))


def test_api_reruns_of_a_structure_trace_and_compile_once(cw_gain_pair, traces, run_compiles):
    a, b = cw_gain_pair
    assert build_loop(a).static_key == build_loop(b).static_key
    programs.clear()
    run_compiles.clear()
    ds_a, m_a = simulate_with_metrics(a)
    assert traces[0] == 1 and len(run_compiles) == 1
    ds_b, m_b = simulate_with_metrics(b)
    assert (
        traces[0] == 1 and len(run_compiles) == 1
    )  # another gain: the same program, not traced again
    assert m_a != m_b  # the gains differ, so do the results
    for scn, ds, m in ((a, ds_a, m_a), (b, ds_b, m_b)):
        ref_ds, ref_m = _fresh(scn)
        assert m == ref_m  # bit for bit
        for name in ref_ds.data_vars:
            np.testing.assert_array_equal(ds[name].values, ref_ds[name].values, err_msg=name)
    assert traces[0] == 3 and len(run_compiles) == 3  # each fresh program was traced and compiled


def test_another_structure_is_traced_and_the_oldest_program_dropped(
    cw_gain_pair, traces, monkeypatch
):
    a, _ = cw_gain_pair
    longer = load_scenario(
        "cw-pd-fault", {"simulation.horizon": 60.0}
    )  # more steps: another structure
    assert build_loop(a).static_key != build_loop(longer).static_key
    monkeypatch.setattr(programs, "_PROGRAMS", LRUCache(maxsize=1))
    monkeypatch.setattr(programs, "_EXECUTABLES", LRUCache(maxsize=1))
    programs.clear()
    simulate_with_metrics(a)
    simulate_with_metrics(longer)
    assert traces[0] == 2 and len(programs._PROGRAMS) == 1
    simulate_with_metrics(longer)
    assert traces[0] == 2  # kept
    assert build_loop(a).static_key not in programs._PROGRAMS  # the oldest program was dropped
    programs.clear()


def test_executable_is_shared_and_lru_bounded(cw_gain_pair, monkeypatch):
    programs.clear()
    c_a, c_b = (build_loop(s) for s in cw_gain_pair)
    exe_a, t_a = programs.executable(c_a)
    exe_b, t_b = programs.executable(c_b)
    assert exe_a is exe_b and t_a > 0.0 and t_b == 0.0
    c_long = build_loop(load_scenario("cw-pd-fault", {"simulation.horizon": 60.0}))
    exe_long, t_long = programs.executable(c_long)  # more steps: another program
    assert exe_long is not exe_a and t_long > 0.0
    out = exe_b(c_b)
    ref = jax.jit(type(c_b).run)(c_b)
    np.testing.assert_array_equal(np.asarray(out["metrics"][0]), np.asarray(ref["metrics"][0]))
    monkeypatch.setattr(programs, "_PROGRAMS", LRUCache(maxsize=1))
    monkeypatch.setattr(programs, "_EXECUTABLES", LRUCache(maxsize=1))
    programs.clear()
    programs.executable(c_a)
    programs.executable(c_long)  # the least recently used (c_a's) is dropped
    assert len(programs._PROGRAMS) == 1  # each shared program keeps its executables
    assert programs.executable(c_long)[1] == 0.0
    assert programs.executable(c_b)[1] > 0.0  # c_a's program was dropped: compiled again
    programs.clear()
