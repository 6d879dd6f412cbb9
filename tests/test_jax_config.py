"""The JAX configuration the package sets on import (``formation_ftc._jax``): float64, the persistent
compilation cache directory (one subdirectory per CPU-client thread count), and its minimum compile
time (JAX's own environment variable overrides the package's 1 s default). Each case runs in a fresh
interpreter: JAX reads its configuration once."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

_PROBE = """
import json, jax
import formation_ftc, formation_ftc._jax
from formation_ftc.report.metadata import provenance
print(json.dumps({"x64": jax.config.jax_enable_x64,
                  "dir": jax.config.jax_compilation_cache_dir,
                  "min": jax.config.jax_persistent_cache_min_compile_time_secs,
                  "threads": provenance()["jax_cpu_threads"]}))
"""


def _probe(tmp_path, **env_extra) -> dict:
    env = {k: v for k, v in os.environ.items()
           if k not in ("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "PJRT_NPROC")}
    env.update({"FORMATION_FTC_JAX_CACHE": str(tmp_path / "cache"), **env_extra})
    proc = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("override, expected", [(None, 0.2), ("0", 0.0), ("1.5", 1.5)])
def test_cache_threshold_defaults_to_a_fifth_of_a_second_and_follows_jax_variable(tmp_path, override, expected):
    extra = {} if override is None else {"JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS": override}
    got = _probe(tmp_path, **extra)
    assert got["x64"] is True
    assert got["min"] == expected


def test_cache_directory_is_keyed_by_the_cpu_client_thread_count(tmp_path):
    """XLA's compiled program depends on the thread count and JAX's cache key does not record it."""
    cores = len(os.sched_getaffinity(0))
    default = _probe(tmp_path)
    assert default["dir"] == str(tmp_path / "cache" / f"cpu-threads-{cores}") and default["threads"] == str(cores)
    for n in ("1", "3"):
        got = _probe(tmp_path, PJRT_NPROC=n)
        assert got["dir"] == str(tmp_path / "cache" / f"cpu-threads-{n}") and got["threads"] == n
        assert (tmp_path / "cache" / f"cpu-threads-{n}").is_dir()


def test_cache_off_also_drops_a_directory_inherited_from_the_parent(tmp_path):
    got = _probe(tmp_path, FORMATION_FTC_JAX_CACHE="off", JAX_COMPILATION_CACHE_DIR=str(tmp_path / "parent"))
    assert got["dir"] is None
