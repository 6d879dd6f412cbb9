"""What importing the package changes process-wide (float64 only), and what
:func:`formation_ftc.sim.runtime.configure` -- the command line's runtime -- adds: the persistent
compilation cache directory (one subdirectory per CPU-client thread count), its minimum compile time
(JAX's own environment variable overrides the package's 0.2 s default), inherited by the processes it
starts. Each case runs in a fresh interpreter: JAX reads its configuration once."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from formation_ftc.sim import runtime

_PROBE = """
import json, os, sys
configure = sys.argv[1] == "configure"
env_before = dict(os.environ)
import formation_ftc
from formation_ftc.sim import runtime
if configure:
    runtime.configure()
import jax
from jax._src.interpreters import mlir
from jax._src.random import threefry2x32 as threefry
jax_rule = mlir._platform_specific_lowerings["cpu"][threefry.threefry2x32_p]  # JAX's own, unless configured
from formation_ftc.report.metadata import provenance
from formation_ftc.sim.runtime import xla
xla.jit(lambda x: x)  # what building a simulation program does
rule = mlir._platform_specific_lowerings["cpu"][threefry.threefry2x32_p]
print(json.dumps({"x64": jax.config.jax_enable_x64,
                  "dir": jax.config.jax_compilation_cache_dir,
                  "min": jax.config.jax_persistent_cache_min_compile_time_secs,
                  "threads": provenance()["jax_cpu_threads"],
                  "env_changed": sorted(k for k in os.environ if os.environ.get(k) != env_before.get(k)),
                  "threefry_unrolled": rule is not jax_rule}))
"""


def _probe(tmp_path, configure: bool = True, **env_extra) -> dict:
    env = {
        k: v
        for k, v in os.environ.items()
        if k
        not in (
            "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS",
            "PJRT_NPROC",
            "JAX_COMPILATION_CACHE_DIR",
            runtime.ENV_SWITCH,
            "JAX_ENABLE_X64",
        )
    }
    env.update({"FORMATION_FTC_JAX_CACHE": str(tmp_path / "cache"), **env_extra})
    proc = subprocess.run(
        [sys.executable, "-c", _PROBE, "configure" if configure else "import"],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_importing_the_package_changes_only_float64(tmp_path):
    got = _probe(tmp_path, configure=False)
    assert got["x64"] is True
    assert got["dir"] is None and not (tmp_path / "cache").exists()  # no cache, no directory made
    assert got["env_changed"] == ["JAX_ENABLE_X64"]
    assert got["threefry_unrolled"] is False  # JAX's own lowering registry untouched


@pytest.fixture(scope="module")
def configured(tmp_path_factory) -> tuple:
    """(its temporary directory, the probe) of a process configured with the package's defaults, read by
    several tests: one interpreter start for all of them."""
    tmp = tmp_path_factory.mktemp("configured")
    return tmp, _probe(tmp)


def test_configure_sets_the_cache_and_tuning_and_is_inherited(configured):
    base, got = configured
    assert got["x64"] is True and got["dir"] is not None and got["threefry_unrolled"] is True
    assert runtime.ENV_SWITCH in got["env_changed"]
    # a process started by a configured one configures itself on import
    child = _probe(base, configure=False, **{runtime.ENV_SWITCH: "on"})
    assert child["dir"] == got["dir"] and child["threefry_unrolled"] is True


@pytest.mark.parametrize("override, expected", [(None, 0.2), ("0", 0.0), ("1.5", 1.5)])
def test_cache_threshold_defaults_to_a_fifth_of_a_second_and_follows_jax_variable(
    tmp_path, configured, override, expected
):
    if override is None:  # the package's default: the shared probe
        got = configured[1]
    else:
        got = _probe(tmp_path, JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS=override)
    assert got["x64"] is True
    assert got["min"] == expected


def test_cache_directory_is_keyed_by_the_cpu_client_thread_count(tmp_path, configured):
    """XLA's compiled program depends on the thread count and JAX's cache key does not record it."""
    cores = len(os.sched_getaffinity(0))
    base, default = configured
    assert default["dir"] == str(base / "cache" / f"cpu-threads-{cores}") and default[
        "threads"
    ] == str(cores)
    for n in ("1", "3"):
        got = _probe(tmp_path, PJRT_NPROC=n)
        assert got["dir"] == str(tmp_path / "cache" / f"cpu-threads-{n}") and got["threads"] == n
        assert (tmp_path / "cache" / f"cpu-threads-{n}").is_dir()


def test_cache_off_also_drops_a_directory_inherited_from_the_parent(tmp_path):
    got = _probe(
        tmp_path, FORMATION_FTC_JAX_CACHE="off", JAX_COMPILATION_CACHE_DIR=str(tmp_path / "parent")
    )
    assert got["dir"] is None
