"""Run provenance for the reproduction report: package versions, git commit, Python, platform, time.

Builds on :func:`formation_ftc.provenance.provenance` (the attributes every result file carries) and
adds what a report reader also wants to know: the versions of the report-side packages (rich,
plotly, pandas, ...), the JAX backend and the host's CPU count. Every value is a string, so the dict
goes unchanged into JSON, NetCDF attributes or an HTML table.
"""

from __future__ import annotations

import datetime as _dt
import os
import platform
import sys
from importlib import metadata

from formation_ftc import provenance as _base

__all__ = ["provenance", "package_versions", "git_commit", "utc_now"]

#: Packages whose versions the report lists, beyond those of :mod:`formation_ftc.provenance`.
EXTRA_PACKAGES = ["h5py", "pandas", "clarabel", "control", "rich", "plotly"]


def utc_now() -> str:
    """Current UTC time, ISO 8601 to the second (e.g. ``2026-11-23T09:40:00+00:00``)."""
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")


def package_versions() -> dict[str, str]:
    """Installed version of every package the toolkit and its report depend on.

    A package that is not installed maps to ``"not installed"`` (plotly is optional).
    """
    out = dict(_base.package_versions())
    for name in EXTRA_PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


def git_commit() -> str:
    """HEAD commit of the checkout the package runs from (``+dirty`` when modified), else ``"unknown"``."""
    return _base.git_commit()


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
    ``created_utc``.
    """
    out = {f"version_{k}": v for k, v in package_versions().items()}
    out.update(
        git_commit=git_commit(),
        python=platform.python_version(),
        python_executable=sys.executable,
        platform=platform.platform(),
        machine=platform.machine(),
        cpu_count=str(os.cpu_count() or "unknown"),
        jax_backend=_jax_backend(),
        created_utc=utc_now(),
    )
    return out
