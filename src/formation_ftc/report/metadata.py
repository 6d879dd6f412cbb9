"""Run provenance for the reproduction report: package versions, git commit, Python, platform, time.

Builds on :func:`formation_ftc.provenance.provenance` (the attributes every result file carries) and
adds what a report reader also wants to know: the Python executable, the JAX backend and the host's
CPU count. Every value is a string, so the dict
goes unchanged into JSON, NetCDF attributes or an HTML table.
"""

from __future__ import annotations

import os
import platform
import sys

from formation_ftc import provenance as _base
from formation_ftc.provenance import git_commit, package_versions, utc_now
from formation_ftc.sim.runtime import cpu_threads as _cpu_threads

__all__ = ["provenance", "package_versions", "git_commit", "utc_now"]


def _jax_backend() -> str:
    try:
        import jax

        devices = jax.devices()
        return f"{jax.default_backend()} ({len(devices)} device{'s' if len(devices) != 1 else ''})"
    except Exception:  # pragma: no cover - jax is a hard dependency; never let provenance fail
        return "unknown"


def provenance() -> dict[str, str]:
    """Flat ``{key: str}`` describing this run's software and machine.

    Keys: ``version_<package>`` for each package (see :func:`package_versions`), ``git_commit``,
    ``python``, ``python_executable``, ``platform``, ``machine``, ``cpu_count``, ``jax_backend``,
    ``jax_cpu_threads`` (the CPU client's thread count, which XLA's compilation depends on; see
    ``formation_ftc.sim.runtime.compilation_cache_dir``), ``created_utc``.
    """
    return {
        **_base.provenance(),
        "python_executable": sys.executable,
        "machine": platform.machine(),
        "cpu_count": str(os.cpu_count() or "unknown"),
        "jax_backend": _jax_backend(),
        "jax_cpu_threads": str(_cpu_threads()),
    }
