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


#: packages the toolkit uses: key written in the result (the import name with ``-`` for ``_``) ->
#: the distributions that install that import name, tried in this order (``cvxpy`` comes from ``cvxpy``
#: or from ``cvxpy-base``). A fixed list read with :func:`importlib.metadata.version`: scanning every
#: installed distribution (``packages_distributions()``) cost 0.6-1.9 s of each run.
_PACKAGES = (
    "formation-ftc jax jaxlib numpy scipy xarray pydantic cvxpy networkx matplotlib dask h5netcdf h5py "
    "pyarrow pandas clarabel control rich plotly"
).split()
_DISTRIBUTIONS: dict[str, tuple[str, ...]] = {
    name: ("cvxpy", "cvxpy-base") if name == "cvxpy" else (name,) for name in _PACKAGES
}


def _version(distributions: tuple[str, ...]) -> str:
    """Version of the first of ``distributions`` that is installed, else "not installed"."""
    for dist in distributions:
        try:
            return metadata.version(dist)
        except metadata.PackageNotFoundError:
            continue
    return "not installed"


@lru_cache(maxsize=1)
def package_versions() -> dict[str, str]:
    """Installed version of each package the toolkit uses ("not installed" for optional ones).

    Returns
    -------
    dict of str to str
        Package (its import name with ``-`` for ``_``) -> version of the distribution that installs it
        (:data:`_DISTRIBUTIONS`; ``cvxpy`` from ``cvxpy`` or ``cvxpy-base``).
    """
    return {name: _version(dists) for name, dists in _DISTRIBUTIONS.items()}


@lru_cache(maxsize=1)
def git_commit() -> str:
    """HEAD commit of the checkout the package runs from ('+dirty' when modified), else 'unknown'."""
    here = Path(__file__).resolve().parent

    def git(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run(["git", *args], cwd=here, capture_output=True, text=True, timeout=5)

    try:
        sha = git("rev-parse", "HEAD")
        sha.check_returncode()
        dirty = git("status", "--porcelain", "--untracked-files=no").stdout.strip()
        return sha.stdout.strip() + ("+dirty" if dirty else "")
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
