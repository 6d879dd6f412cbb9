"""Fixtures for the Li2020 tests: the paper's composed scenarios (``[scenario] paper = "li2020"``) loaded
and run through the generic API."""

from __future__ import annotations

import pytest

import formation_ftc  # noqa: F401  (x64)
from formation_ftc.api import load_scenario as load_li2020
from formation_ftc.papers.programs import simulate as simulate_li2020


@pytest.fixture(scope="session")
def load():
    return load_li2020


@pytest.fixture(scope="session")
def simulate():
    return simulate_li2020


@pytest.fixture(scope="module")
def thm1_full():
    """Full 3000 s Thm 1 run (a few seconds), shared by the tests of a module."""
    return simulate_li2020(load_li2020("li2020-thm1"))
