"""Provenance recorded in every result file: package versions, git commit, platform, time."""

from __future__ import annotations

import datetime as _dt
import platform
import subprocess
from functools import lru_cache
from importlib import metadata
from pathlib import Path

__all__ = ["package_versions", "git_commit", "provenance", "utc_now"]


def utc_now() -> str:
    """Current UTC time, ISO 8601 to the second (e.g. ``2026-11-23T09:40:00+00:00``)."""
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")

_PACKAGES = ["formation-ftc", "jax", "jaxlib", "numpy", "scipy", "xarray", "pydantic", "cvxpy",
             "networkx", "matplotlib", "dask", "h5netcdf", "h5py", "pyarrow", "pandas", "clarabel",
             "control", "rich", "plotly"]


@lru_cache(maxsize=1)
def package_versions() -> dict[str, str]:
    """Installed version of each package the toolkit uses ("not installed" for optional ones)."""
    out = {}
    for name in _PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


@lru_cache(maxsize=1)
def git_commit() -> str:
    """HEAD commit of the checkout the package runs from ('+dirty' when modified), else 'unknown'."""
    here = Path(__file__).resolve().parent
    try:
        sha = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True,
                             timeout=5, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=here,
                               capture_output=True, text=True, timeout=5).stdout.strip()
        return sha + ("+dirty" if dirty else "")
    except Exception:
        return "unknown"


def provenance() -> dict[str, str]:
    """Flat string dict suitable for NetCDF attributes and JSON."""
    out = {f"version_{k}": v for k, v in package_versions().items()}
    out.update(
        git_commit=git_commit(),
        python=platform.python_version(),
        platform=platform.platform(),
        created_utc=utc_now(),
    )
    return out
