"""Shared helpers for the campaign tests: tiny CW campaigns (200 steps) that run in seconds."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest
import tomli_w

#: A 2 x 3 campaign on the lead's cw-pd-fault scenario cut to 20 s (200 RK4 steps of 0.1 s).
TINY = {
    "campaign": {
        "name": "tiny",
        "base": "cw-pd-fault",
        "runs": 3,
        "seed": 11,
        "chunk_size": 2,
        "metrics": ["max_position_error", "final_position_error_mean", "delta_v_total"],
    },
    "overrides": {"simulation.horizon": 20.0},
    "sample": {
        "controller.kp": {"dist": "uniform", "low": 1.0, "high": 3.0},
        "controller.kd": {"grid": [10.0, 30.0]},
        "plant.mass.0": {"dist": "normal", "mean": 100.0, "std": 5.0, "low": 80.0},
    },
    "traces": {"runs": [0, 4], "every": 2},
}


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
