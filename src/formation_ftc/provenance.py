"""Provenance recorded in every result file: package versions, git commit, platform, time."""

from __future__ import annotations

import datetime as _dt
import platform
import subprocess
from collections.abc import Mapping
from functools import lru_cache
from importlib import metadata
from pathlib import Path

__all__ = ["package_versions", "git_commit", "provenance", "utc_now"]


def utc_now() -> str:
    """Current UTC time, ISO 8601 to the second (e.g. ``2026-11-23T09:40:00+00:00``)."""
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")


#: packages the toolkit uses, by import name; the key of each version is the name written here
_PACKAGES = [
    "formation_ftc",
    "jax",
    "jaxlib",
    "numpy",
    "scipy",
    "xarray",
    "pydantic",
    "cvxpy",
    "networkx",
    "matplotlib",
    "dask",
    "h5netcdf",
    "h5py",
    "pyarrow",
    "pandas",
    "clarabel",
    "control",
    "rich",
    "plotly",
]


def _version(import_name: str, providers: Mapping[str, list[str]]) -> str:
    """Version of the distribution that installed ``import_name`` (``cvxpy`` comes from ``cvxpy`` or
    ``cvxpy-base``), else of the distribution of the same name, else "not installed"."""
    for dist in dict.fromkeys([*providers.get(import_name, []), import_name]):
        try:
            return metadata.version(dist)
        except metadata.PackageNotFoundError:
            continue
    return "not installed"


@lru_cache(maxsize=1)
def package_versions() -> dict[str, str]:
    """Installed version of each package the toolkit uses ("not installed" for optional ones), read from
    the metadata of the distribution that provides its import name
    (:func:`importlib.metadata.packages_distributions`); key: the import name with ``-`` for ``_``."""
    providers = metadata.packages_distributions()
    return {name.replace("_", "-"): _version(name, providers) for name in _PACKAGES}


@lru_cache(maxsize=1)
def git_commit() -> str:
    """HEAD commit of the checkout the package runs from ('+dirty' when modified), else 'unknown'."""
    here = Path(__file__).resolve().parent
    try:
        sha = subprocess.run(
            ["git", "rev-parse", "HEAD"],
            cwd=here,
            capture_output=True,
            text=True,
            timeout=5,
            check=True,
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=here,
            capture_output=True,
            text=True,
            timeout=5,
        ).stdout.strip()
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
