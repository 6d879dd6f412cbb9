"""Compiled programs kept on disk under a key known before tracing (formation_ftc.sim.runtime.program_cache).

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

from formation_ftc.sim.runtime import program_cache as pc

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
    proc = subprocess.run(
        [sys.executable, "-c", _CHILD], capture_output=True, text=True, env=environ, timeout=300
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.slow
def test_a_stored_program_is_loaded_untraced_and_gives_the_same_bits(tmp_path):
    first = _child(tmp_path / "cache")  # cold: traces, compiles, stores
    entries = list((tmp_path / "cache").rglob("programs/*.bin"))
    assert first["run_traces"] == 1 and len(entries) == 1
    second = _child(tmp_path / "cache")  # warm: loads the entry, no trace of the closed loop
    assert second["run_traces"] == 0
    off = _child(
        tmp_path / "other", FORMATION_FTC_PROGRAM_CACHE="off"
    )  # compiled in its own process
    assert off["run_traces"] == 1 and not list((tmp_path / "other").rglob("programs/*.bin"))
    for got in (second, off):
        assert got["records"] == first["records"] and got["metrics"] == first["metrics"]


def test_the_key_changes_with_every_input_and_not_otherwise():
    args = (np.zeros(3), np.float64(1.0))
    base = pc.program_key("run", ("a", 1), args)
    assert base is not None and base == pc.program_key(
        "run", ("a", 1), (np.ones(3), np.float64(2.0))
    )
    others = [
        pc.program_key("batch", ("a", 1), args),
        pc.program_key("run", ("a", 2), args),
        pc.program_key("run", ("a", 1), (np.zeros(4), np.float64(1.0))),  # a shape
        pc.program_key("run", ("a", 1), (np.zeros(3, np.int64), np.float64(1.0))),  # a dtype
        pc.program_key("run", ("a", 1), (np.zeros(3), 1.0)),  # a weak type (Python float)
        pc.program_key("run", ("a", 1), [np.zeros(3), np.float64(1.0)]),
    ]  # the tree
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
    assert (
        pc.program_key("run", ("loop", np.tanh), (np.zeros(1),)) is not None
    )  # a library function


def test_a_corrupted_entry_is_removed_and_the_program_compiled(tmp_path, monkeypatch):
    import jax

    monkeypatch.setattr(pc, "directory", lambda: tmp_path)
    args = (np.arange(3.0),)
    key = pc.program_key("test", "double", args)
    (tmp_path / f"{key}.bin").write_bytes(b"not an executable")
    exe = pc.load_or_compile(jax.jit(lambda x: 2.0 * x), "test", "double", args)
    np.testing.assert_array_equal(np.asarray(exe(*args)), [0.0, 2.0, 4.0])
    entry = (
        tmp_path / f"{key}.bin"
    )  # removed; stored again when XLA compiled it (not a JAX-cache load)
    assert not entry.exists() or entry.read_bytes() != b"not an executable"


def test_switched_off_and_without_a_jax_cache_there_is_no_directory(monkeypatch):
    from types import SimpleNamespace

    monkeypatch.setenv(pc.ENV_SWITCH, "off")
    assert pc.directory() is None
    monkeypatch.setenv(pc.ENV_SWITCH, "on")
    monkeypatch.setattr(
        pc, "jax", SimpleNamespace(config=SimpleNamespace(jax_compilation_cache_dir="/c"))
    )
    assert str(pc.directory()) == os.path.join("/c", "programs")
    monkeypatch.setattr(
        pc, "jax", SimpleNamespace(config=SimpleNamespace(jax_compilation_cache_dir=None))
    )
    assert pc.directory() is None  # FORMATION_FTC_JAX_CACHE=off


def test_only_programs_whose_custom_calls_a_loader_prepares_are_stored():
    class Exe:
        def __init__(self, text):
            self.text = text

        def as_text(self):
            return self.text

    assert pc._storable(Exe("ROOT %a = f64[3] add(...)"))
    assert pc._storable(
        Exe('custom_call_target="lapack_dgetrf_ffi" custom_call_target="lapack_dtrsm_ffi"')
    )
    assert not pc._storable(
        Exe('custom_call_target="lapack_dgetrf_ffi" custom_call_target="my_kernel"')
    )


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
    np.testing.assert_array_equal(
        np.asarray(exe(np.full(2, 3.0))), [6.0, 6.0]
    )  # the fresh one from now on


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


# --- safety: nothing in the cache directory is trusted unless this user wrote it -------------------------


def _fresh_program():
    """A jitted function no cache has seen (a random constant), its arguments and its result."""
    import jax

    scale = float(np.random.default_rng().uniform(1.0, 2.0))
    args = (np.arange(4.0),)
    return jax.jit(lambda x: scale * x + 1.0), args, scale * np.arange(4.0) + 1.0


def _stored(folder, kind="test", parts="p"):
    """Store a freshly compiled program under (kind, parts) in ``folder``; returns (path, args, result)."""
    jitted, args, expected = _fresh_program()
    assert pc._safe_folder(folder)
    key = pc.program_key(kind, parts, args)
    path = folder / f"{key}.bin"
    pc._store(path, key, pc._secret(folder), jitted.lower(*args).compile())
    assert path.is_file()
    return path, args, expected


@pytest.fixture
def folder(tmp_path, monkeypatch):
    programs = tmp_path / "cache" / "programs"
    monkeypatch.setattr(pc, "directory", lambda: programs)
    pc._SECRETS.clear()
    yield programs
    pc._SECRETS.clear()


def test_the_directory_key_and_entries_are_private_to_this_user(folder):
    path, args, expected = _stored(folder)
    assert os.stat(folder).st_mode & 0o777 == 0o700
    assert os.stat(folder / pc._SECRET_FILE).st_mode & 0o777 == 0o600
    assert os.stat(path).st_mode & 0o777 == 0o600
    exe = pc.load_or_compile(None, "test", "p", args)  # loaded: no jitted function is needed
    np.testing.assert_array_equal(np.asarray(exe(*args)), expected)


def test_a_planted_pickle_is_never_unpickled(folder, tmp_path):
    import pickle

    import jax

    marker = tmp_path / "pwned"

    class Payload:
        def __reduce__(self):
            return (os.system, (f"touch {marker}",))

    args = (np.arange(3.0),)
    assert pc._safe_folder(folder)
    key = pc.program_key("test", "double", args)
    entry = folder / f"{key}.bin"
    import zlib

    for blob in (
        pickle.dumps(Payload()),
        zlib.compress(pickle.dumps((Payload(), None, None))),
        pc.MAGIC + key.encode() + b"\0" * 32 + zlib.compress(pickle.dumps(Payload())),
    ):
        entry.write_bytes(blob)
        os.chmod(entry, 0o600)
        exe = pc.load_or_compile(jax.jit(lambda x: 2.0 * x), "test", "double", args)
        np.testing.assert_array_equal(np.asarray(exe(*args)), [0.0, 2.0, 4.0])
        assert not marker.exists()
        assert (
            not entry.exists() or entry.read_bytes() != blob
        )  # removed (or replaced by a real entry)


def test_an_entry_owned_by_another_user_or_writable_by_others_is_not_loaded(folder, monkeypatch):
    import jax

    path, args, expected = _stored(folder)
    good = path.read_bytes()
    wrong = jax.jit(lambda x: -x)  # what a refused entry must give: the program compiled here
    os.chmod(path, 0o666)
    np.testing.assert_array_equal(
        np.asarray(pc.load_or_compile(wrong, "test", "p", args)(*args)), -args[0]
    )
    assert not path.exists() or path.read_bytes() != good
    # another owner: really (as root), else as this process would see it
    path.write_bytes(good)
    os.chmod(path, 0o600)
    if os.geteuid() == 0:
        os.chown(path, 65534, 65534)
    else:
        real = os.geteuid()
        monkeypatch.setattr(pc.os, "geteuid", lambda: real + 1)
        pc._SECRETS.clear()
    assert pc._load(path, pc.program_key("test", "p", args), b"k" * 32, args) is None
    assert not path.exists()


def test_a_directory_writable_by_others_switches_the_cache_off_and_is_left_alone(folder):
    import jax

    path, args, expected = _stored(folder)
    os.chmod(folder, 0o777)
    with pytest.warns(pc.UnsafeCacheWarning, match="not a directory owned by this user"):
        exe = pc.load_or_compile(jax.jit(lambda x: -x), "test", "p", args)
    np.testing.assert_array_equal(np.asarray(exe(*args)), -args[0])  # compiled, not loaded
    assert path.is_file()  # not ours to clean: untouched
    os.chmod(folder, 0o700)
    os.chmod(folder.parent, 0o757)  # the parent counts too (the folder could be swapped from there)
    with pytest.warns(pc.UnsafeCacheWarning):
        pc._WARNED.clear()
        assert not pc._safe_folder(folder)


def test_an_entry_under_another_programs_name_is_refused_and_removed(folder):
    import jax

    a_path, args, a_result = _stored(folder, parts="A")
    b_key = pc.program_key("test", "B", args)
    b_path = folder / f"{b_key}.bin"
    b_path.write_bytes(a_path.read_bytes())
    os.chmod(b_path, 0o600)
    exe = pc.load_or_compile(jax.jit(lambda x: -x), "test", "B", args)
    np.testing.assert_array_equal(np.asarray(exe(*args)), -args[0])  # B's own numbers, not A's
    assert not b_path.exists() or b_path.read_bytes() != a_path.read_bytes()
    # A altered by one byte fails its tag: removed, compiled
    blob = bytearray(a_path.read_bytes())
    blob[-1] ^= 1
    a_path.write_bytes(bytes(blob))
    exe = pc.load_or_compile(jax.jit(lambda x: -x), "test", "A", args)
    np.testing.assert_array_equal(np.asarray(exe(*args)), -args[0])
    assert not a_path.exists()


def test_a_key_file_that_is_not_private_is_replaced_and_its_entries_fail(folder):
    path, args, _ = _stored(folder)
    key_file = folder / pc._SECRET_FILE
    old = key_file.read_bytes()
    os.chmod(key_file, 0o644)  # readable by others: anyone could sign entries
    pc._SECRETS.clear()
    new = pc._secret(folder)
    assert new is not None and new != old and os.stat(key_file).st_mode & 0o777 == 0o600
    assert (
        pc._load(path, pc.program_key("test", "p", args), new, args) is None and not path.exists()
    )


def test_an_entry_that_fails_on_its_first_call_for_any_reason_is_removed(tmp_path):
    import jax

    class Broken:
        def __call__(self, *args):
            raise ValueError("an executable that does not match its arguments")

    entry = tmp_path / "k.bin"
    entry.write_bytes(b"entry")
    exe = pc._CheckedOnFirstCall(
        Broken(), entry, lambda: jax.jit(lambda x: 2.0 * x).lower(np.ones(2)).compile()
    )
    np.testing.assert_array_equal(np.asarray(exe(np.ones(2))), [2.0, 2.0])
    assert not entry.exists()


def test_result_trees_round_trip_through_json_and_foreign_classes_are_refused():
    import collections

    import jax

    from formation_ftc.blocks.supervisors.hierarchical_supervisor import (
        HlState,
    )  # a package named tuple

    state = HlState(*range(len(HlState._fields)))
    tree = jax.tree_util.tree_structure({"a": (1, None, [2, ()]), "b": {"c": 3}, "s": state})
    assert pc._tree_from_json(json.loads(json.dumps(pc._tree_to_json(tree)))) == tree
    Local = collections.namedtuple("Local", "x")
    with pytest.raises(pc.Uncacheable):
        pc._tree_to_json(jax.tree_util.tree_structure(Local(1)))
    with pytest.raises(ValueError, match="untrusted"):
        pc._tree_from_json(["os:system", None, []])
    with pytest.raises(ValueError, match="not a named tuple"):
        pc._tree_from_json(["formation_ftc.sim.runtime.program_cache:CachedProgram", None, []])


def test_a_compilation_cache_directory_writable_by_others_is_not_used(tmp_path, capsys):
    from formation_ftc.sim import runtime

    shared = tmp_path / "shared"
    shared.mkdir()
    assert runtime.private_cache_dir(str(shared / "cpu-threads-2"))
    os.chmod(shared, 0o777)
    assert not runtime.private_cache_dir(str(shared / "cpu-threads-2"))
    assert "compilation cache off" in capsys.readouterr().err
