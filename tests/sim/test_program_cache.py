"""Compiled programs kept on disk under a key known before tracing (formation_ftc.sim.program_cache).

Truths: a second process with a fresh persistent cache that compiles the same scenario itself (the
results of a loaded program must equal a program traced and compiled in the process, bit for bit);
JAX's own trace events (``jax.monitoring``: a loaded program is not traced); the key's inputs changed
one at a time (each must change the key); corrupted entries (must be removed and recompiled).
"""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from formation_ftc.sim import program_cache as pc

# One process: run azizi2009-llfr (its step solves with LAPACK, the custom call a loading process must
# prepare) for 0.2 s through the API and print the run program's traces and a digest of the results.
_CHILD = textwrap.dedent("""
    import hashlib, json, sys
    import jax.monitoring
    traces = []
    jax.monitoring.register_event_duration_secs_listener(
        lambda e, d, **kw: traces.append(kw.get("fun_name"))
        if e == "/jax/core/compile/jaxpr_trace_duration" else None)
    import numpy as np
    from formation_ftc import api
    ds, metrics = api.simulate_with_metrics(api.load_scenario("azizi2009-llfr", {"simulation.horizon": 0.2}))
    h = hashlib.sha256()
    for name in sorted(ds.data_vars):
        h.update(np.ascontiguousarray(ds[name].values).tobytes())
    print(json.dumps({"run_traces": traces.count("run"), "records": h.hexdigest(),
                      "metrics": {k: repr(v) for k, v in metrics.items()}}))
""")


def _child(cache_dir, **env) -> dict:
    environ = {**os.environ, "FORMATION_FTC_JAX_CACHE": str(cache_dir), **env}
    environ.pop("FORMATION_FTC_PROGRAM_CACHE", None)
    environ.update(env)
    proc = subprocess.run([sys.executable, "-c", _CHILD], capture_output=True, text=True, env=environ,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.slow
def test_a_stored_program_is_loaded_untraced_and_gives_the_same_bits(tmp_path):
    first = _child(tmp_path / "cache")  # cold: traces, compiles, stores
    entries = list((tmp_path / "cache").rglob("programs/*.bin"))
    assert first["run_traces"] == 1 and len(entries) == 1
    second = _child(tmp_path / "cache")  # warm: loads the entry, no trace of the closed loop
    assert second["run_traces"] == 0
    off = _child(tmp_path / "other", FORMATION_FTC_PROGRAM_CACHE="off")  # compiled in its own process
    assert off["run_traces"] == 1 and not list((tmp_path / "other").rglob("programs/*.bin"))
    for got in (second, off):
        assert got["records"] == first["records"] and got["metrics"] == first["metrics"]


def test_the_key_changes_with_every_input_and_not_otherwise():
    args = (np.zeros(3), np.float64(1.0))
    base = pc.program_key("run", ("a", 1), args)
    assert base is not None and base == pc.program_key("run", ("a", 1), (np.ones(3), np.float64(2.0)))
    others = [pc.program_key("batch", ("a", 1), args), pc.program_key("run", ("a", 2), args),
              pc.program_key("run", ("a", 1), (np.zeros(4), np.float64(1.0))),  # a shape
              pc.program_key("run", ("a", 1), (np.zeros(3, np.int64), np.float64(1.0))),  # a dtype
              pc.program_key("run", ("a", 1), (np.zeros(3), 1.0)),  # a weak type (Python float)
              pc.program_key("run", ("a", 1), [np.zeros(3), np.float64(1.0)])]  # the tree
    assert None not in others and len({base, *others}) == len(others) + 1


def test_the_key_changes_with_the_environment_and_the_package_source(monkeypatch):
    args = (np.zeros(2),)
    base = pc.program_key("run", "p", args)
    monkeypatch.setenv("XLA_FLAGS", "--xla_cpu_enable_fast_math=false")
    assert pc.program_key("run", "p", args) != base
    monkeypatch.delenv("XLA_FLAGS")
    monkeypatch.setenv("FORMATION_FTC_XLA_OPTIONS", "off")
    assert pc.program_key("run", "p", args) != base
    monkeypatch.delenv("FORMATION_FTC_XLA_OPTIONS")
    monkeypatch.setattr(pc, "_source_digest", lambda: "0" * 64)
    assert pc.program_key("run", "p", args) != base


@dataclasses.dataclass(frozen=True)
class _OutsideComponent:
    """A component class defined outside formation_ftc (here: in a test module), as a plugin's would be."""

    gain: float = 1.0


def test_code_from_outside_the_package_is_not_keyed():
    assert pc.program_key("run", ("loop", _OutsideComponent()), (np.zeros(1),)) is None
    assert pc.program_key("run", ("loop", lambda x: x), (np.zeros(1),)) is None  # no stable name
    assert pc.program_key("run", ("loop", np.tanh), (np.zeros(1),)) is not None  # a library function


def test_a_corrupted_entry_is_removed_and_the_program_compiled(tmp_path, monkeypatch):
    import jax

    monkeypatch.setattr(pc, "directory", lambda: tmp_path)
    args = (np.arange(3.0),)
    key = pc.program_key("test", "double", args)
    (tmp_path / f"{key}.bin").write_bytes(b"not an executable")
    exe = pc.load_or_compile(jax.jit(lambda x: 2.0 * x), "test", "double", args)
    np.testing.assert_array_equal(np.asarray(exe(*args)), [0.0, 2.0, 4.0])
    entry = tmp_path / f"{key}.bin"  # removed; stored again when XLA compiled it (not a JAX-cache load)
    assert not entry.exists() or entry.read_bytes() != b"not an executable"


def test_switched_off_and_without_a_jax_cache_there_is_no_directory(monkeypatch):
    from types import SimpleNamespace

    monkeypatch.setenv(pc.ENV_SWITCH, "off")
    assert pc.directory() is None
    monkeypatch.setenv(pc.ENV_SWITCH, "on")
    monkeypatch.setattr(pc, "jax", SimpleNamespace(config=SimpleNamespace(jax_compilation_cache_dir="/c")))
    assert str(pc.directory()) == os.path.join("/c", "programs")
    monkeypatch.setattr(pc, "jax", SimpleNamespace(config=SimpleNamespace(jax_compilation_cache_dir=None)))
    assert pc.directory() is None  # FORMATION_FTC_JAX_CACHE=off


def test_only_programs_whose_custom_calls_a_loader_prepares_are_stored():
    class Exe:
        def __init__(self, text):
            self.text = text

        def as_text(self):
            return self.text

    assert pc._storable(Exe("ROOT %a = f64[3] add(...)"))
    assert pc._storable(Exe('custom_call_target="lapack_dgetrf_ffi" custom_call_target="lapack_dtrsm_ffi"'))
    assert not pc._storable(Exe('custom_call_target="lapack_dgetrf_ffi" custom_call_target="my_kernel"'))


def test_the_key_changes_inside_a_jax_configuration_context():
    import jax

    args = (np.zeros(2),)
    base = pc.program_key("run", "p", args)
    with jax.default_matmul_precision("float32"):
        assert pc.program_key("run", "p", args) != base
    assert pc.program_key("run", "p", args) == base


def test_only_what_xla_compiled_in_this_call_is_stored(tmp_path, monkeypatch):
    # an executable that JAX loaded from its persistent cache (or kept in memory after such a load)
    # serializes without its kernels: only an executable JAX has just compiled, and written to its own
    # cache, goes to disk
    import jax

    if not getattr(jax.config, "jax_compilation_cache_dir", None):
        pytest.skip("JAX's persistent cache is off (FORMATION_FTC_JAX_CACHE=off)")
    old = jax.config.jax_persistent_cache_min_compile_time_secs
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    try:
        monkeypatch.setattr(pc, "directory", lambda: tmp_path)
        scale = float(np.random.default_rng().uniform(1.0, 2.0))  # a program no cache has seen
        args = (np.arange(4.0),)
        exe = pc.load_or_compile(jax.jit(lambda x: scale * x + 1.0), "test", "fresh", args)
        assert len(list(tmp_path.glob("*.bin"))) == 1  # compiled here: stored
        # the same program again under another key: JAX's in-memory cache answers, nothing is stored
        again = pc.load_or_compile(jax.jit(lambda x: scale * x + 1.0), "test", "again", args)
        assert len(list(tmp_path.glob("*.bin"))) == 1
        np.testing.assert_array_equal(np.asarray(again(*args)), np.asarray(exe(*args)))
        # and the stored one loads and gives the same bits
        loaded = pc.load_or_compile(jax.jit(lambda x: x), "test", "fresh", args)
        assert isinstance(loaded, pc._CheckedOnFirstCall)
        np.testing.assert_array_equal(np.asarray(loaded(*args)), np.asarray(exe(*args)))
    finally:
        jax.config.update("jax_persistent_cache_min_compile_time_secs", old)


def test_an_entry_that_loads_but_cannot_run_is_removed_and_the_program_compiled(tmp_path):
    import jax

    class Broken:
        def __call__(self, *args):
            raise jax.errors.JaxRuntimeError("NOT_FOUND: Function fusion.1 not found (type id: 1)")

    entry = tmp_path / "k.bin"
    entry.write_bytes(b"entry")
    fresh = jax.jit(lambda x: 2.0 * x).lower(np.ones(2)).compile()
    exe = pc._CheckedOnFirstCall(Broken(), entry, lambda: fresh)
    np.testing.assert_array_equal(np.asarray(exe(np.ones(2))), [2.0, 2.0])
    assert not entry.exists()
    np.testing.assert_array_equal(np.asarray(exe(np.full(2, 3.0))), [6.0, 6.0])  # the fresh one from now on


def test_jax_debugging_modes_call_the_jitted_function_itself():
    import jax

    calls = []

    def jitted(x):
        calls.append(x)
        return x

    program = pc.CachedProgram(jitted, "test", "debug")
    with jax.debug_nans(True):
        assert program(1.0) == 1.0
    assert calls == [1.0]
