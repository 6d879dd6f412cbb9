"""Sensors ``lvlh-relative-state`` on a plant whose sensed state has no (N, 6) LVLH relative state:
refused by validation, naming both parts (the sensors' output and statistics are tested with the
truth plant they were written for, tests/components/plants/test_orbital_truth.py)."""

from __future__ import annotations

import copy

import pytest

from formation_ftc.api import load_scenario
from formation_ftc.config import loader
from formation_ftc.config.loader import ScenarioError


def test_refused_on_a_plant_without_the_lvlh_relative_state():
    raw = copy.deepcopy(loader.read_raw("azizi2009-fault-free")[0])  # positions r, v: no q
    raw["sensors"] = {"type": "lvlh-relative-state"}
    with pytest.raises(ScenarioError) as err:
        load_scenario(raw)
    msg = str(err.value)
    assert "sensors lvlh-relative-state needs the (N, 6) LVLH relative state" in msg, msg
    assert 'plant type = "clohessy-wiltshire"' in msg, msg
