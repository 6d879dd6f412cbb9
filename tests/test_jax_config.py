"""The JAX configuration the package sets on import (``formation_ftc._jax``): float64, the persistent
compilation cache directory, and its minimum compile time (JAX's own environment variable overrides the
package's 1 s default). Each case runs in a fresh interpreter: JAX reads its configuration once."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

_PROBE = """
import json, jax
import formation_ftc
print(json.dumps({"x64": jax.config.jax_enable_x64,
                  "dir": jax.config.jax_compilation_cache_dir,
                  "min": jax.config.jax_persistent_cache_min_compile_time_secs}))
"""


def _probe(tmp_path, **env_extra) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"}
    env.update(FORMATION_FTC_JAX_CACHE=str(tmp_path / "cache"), **env_extra)
    proc = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("override, expected", [(None, 1.0), ("0", 0.0), ("0.25", 0.25)])
def test_cache_threshold_defaults_to_one_second_and_follows_jax_variable(tmp_path, override, expected):
    extra = {} if override is None else {"JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS": override}
    got = _probe(tmp_path, **extra)
    assert got["x64"] is True
    assert got["dir"] == str(tmp_path / "cache") and (tmp_path / "cache").is_dir()
    assert got["min"] == expected

