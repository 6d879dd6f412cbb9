"""Shared helpers for the campaign tests: tiny CW campaigns (200 steps) that run in seconds."""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

import pytest
import tomli_w

#: A 2 x 3 campaign on the lead's cw-pd-fault scenario cut to 20 s (200 RK4 steps of 0.1 s).
TINY_FILE = Path(__file__).with_name("tiny-campaign.toml")
TINY = tomllib.loads(TINY_FILE.read_text())


def _tiny(**campaign) -> dict:
    raw = copy.deepcopy(TINY)
    raw["campaign"].update(campaign)
    return raw


def _write_campaign(path: Path, raw: dict) -> Path:
    path.write_text(tomli_w.dumps(raw))
    return path


@pytest.fixture
def tiny():
    """Factory: ``tiny(**campaign_fields) -> raw campaign dict`` (a fresh copy)."""
    return _tiny


@pytest.fixture
def write_campaign():
    """``write_campaign(path, raw) -> path`` of the TOML file."""
    return _write_campaign
