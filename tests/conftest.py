"""Shared test configuration: float64 JAX for every test; the long end-to-end checks start first.

Tests marked ``slow`` (full reproductions, multi-process campaign checks) are moved to the front of
the collection (their relative order kept). Under ``pytest -n 2`` the workers then start on the
longest tests and share the many short ones afterwards, instead of one worker finishing a long test
alone at the end; run serially, the order of the other tests is unchanged.
"""

import formation_ftc  # noqa: F401  (enables jax_enable_x64)


def pytest_collection_modifyitems(session, config, items):
    """Stable partition: ``slow``-marked tests first (same order on every xdist worker)."""
    slow = [it for it in items if it.get_closest_marker("slow") is not None]
    if slow and config.getoption("numprocesses", default=None):
        rest = [it for it in items if it.get_closest_marker("slow") is None]
        items[:] = slow + rest
