"""The named, versioned fault battery: loader, errors, and the fields it gives the composed sections."""

from __future__ import annotations

import hashlib
import tomllib
from pathlib import Path

import pytest
import tomli_w

import formation_ftc as ftc
from formation_ftc.components.actuators.fault_battery import FAULT_KINDS
from formation_ftc.league.battery import (
    COMMUNICATION_KINDS,
    BatteryError,
    builtin_batteries,
    load_battery,
)
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import structure_key


def test_v1_loads_with_version_hash_and_every_kind():
    b = load_battery("v1")
    assert b.name == "v1" and b.version == 1
    assert b.sha256 == hashlib.sha256(builtin_batteries()["v1"].read_bytes()).hexdigest()
    assert b.label.startswith("v1 v1 sha256:")
    assert set(c.kind for c in b) == set(FAULT_KINDS) | set(COMMUNICATION_KINDS)
    assert len(set(b.names)) == len(b) == 9
    loe, deg, inter = b["loe-50"], b["degrading"], b["intermittent"]
    assert (
        loe.effectiveness == 0.5 and loe.spacecraft == 2 and loe.axis == 0 and loe.onset == 1000.0
    )
    assert deg.rate * 1000.0 == pytest.approx(1.0 - deg.min_effectiveness)  # 1 -> 0.2 over 1000 s
    assert (inter.period, inter.duty) == (60.0, 0.5)
    assert b["link-loss"].lost_links == ((3, 4),)


def test_unknown_battery_lists_the_known_ones():
    with pytest.raises(BatteryError, match=r"unknown fault battery 'v9' \(known: v1"):
        load_battery("v9")
    with pytest.raises(BatteryError, match="no case 'jammed'"):
        load_battery("v1")["jammed"]


def _write(tmp_path: Path, raw: dict) -> Path:
    p = tmp_path / "battery-test.toml"
    p.write_bytes(tomli_w.dumps(raw).encode())
    return p


def _raw(*cases, defaults=None):
    return {
        "battery": {"name": "test", "version": 2},
        "defaults": defaults or {},
        "cases": list(cases),
    }


@pytest.mark.parametrize(
    "raw, needle",
    [
        (
            _raw({"name": "a", "kind": "jammed"}),
            "cases[0] (a).kind: Value error, kind = 'jammed' is not a fault kind "
            "(allowed: none, loss_of_effectiveness",
        ),
        (
            _raw({"name": "a", "kind": "loss_of_effectiveness"}),
            "kind loss_of_effectiveness needs effectiveness",
        ),
        (
            _raw({"name": "a", "kind": "bias", "bias_force": 1.0}),
            "needs bias_fraction, bias_torque",
        ),
        (
            _raw({"name": "a", "kind": "none"}, {"name": "a", "kind": "outage"}),
            "duplicate case names a",
        ),
        (_raw({"name": "a", "kind": "none", "magnitude": 1.0}), "cases[0] (a).magnitude"),
        (
            _raw({"name": "a", "kind": "none"}, defaults={"sc": 1}),
            "defaults: sc cannot be defaults",
        ),
        (_raw({"name": "a", "kind": "stuck", "axis": 3}), "cases[0] (a).axis"),
        (_raw({"name": "a", "kind": "link_loss", "lost_links": [[2, 2]]}), "receiver != sender"),
        (
            {"battery": {"name": "t", "version": 0}, "cases": [{"name": "a", "kind": "none"}]},
            "battery.version",
        ),
    ],
)
def test_bad_battery_files_are_rejected_naming_the_field(tmp_path, raw, needle):
    with pytest.raises(BatteryError) as err:
        load_battery(_write(tmp_path, raw))
    assert needle in str(err.value)


def test_not_toml(tmp_path):
    p = tmp_path / "b.toml"
    p.write_text("[battery\n")
    with pytest.raises(BatteryError, match="not valid TOML"):
        load_battery(p)


def test_defaults_apply_and_cases_override(tmp_path):
    b = load_battery(
        _write(
            tmp_path,
            _raw(
                {"name": "a", "kind": "outage"},
                {"name": "b", "kind": "outage", "axis": 2},
                defaults={"spacecraft": 3, "axis": 1, "onset": 5.0},
            ),
        )
    )
    assert (b["a"].spacecraft, b["a"].axis, b["a"].onset) == (3, 1, 5.0)
    assert b["b"].axis == 2 and b.version == 2


def test_actuator_fields():
    b = load_battery("v1")
    bias = b["bias"]
    assert bias.actuator_fields(saturation=0.2)["bias"] == pytest.approx(0.1)  # half the limit
    assert bias.actuator_fields(saturation=0.2)["saturation"] == 0.2
    # per-spacecraft limits: the faulty spacecraft's (2) limit
    assert bias.actuator_fields(saturation=[0.1, 0.4, 0.3, 0.2])["bias"] == pytest.approx(0.2)
    assert bias.actuator_fields()["bias"] == 1.0 and "saturation" not in bias.actuator_fields()
    assert bias.actuator_fields(saturation=float("inf"))["bias"] == 1.0
    assert bias.actuator_fields(quantity="torque")["bias"] == 0.5
    assert b["link-loss"].actuator_fields()["kind"] == "none"
    assert b["stuck"].actuator_fields(onset=123.0)["onset"] == 123.0
    keys = {frozenset(c.actuator_fields(saturation=1.0)) for c in b}
    assert len(keys) == 1  # every case gives the same fields
    with pytest.raises(BatteryError, match="quantity"):
        bias.actuator_fields(quantity="acceleration")


def test_network_fields_and_applicability():
    b = load_battery("v1")
    assert b["link-loss"].network_fields()["lost_links"] == [[3, 4]]
    assert b["loe-50"].network_fields() == {
        "type": "graph-link-loss",
        "lost_links": [],
        "onset": 1000.0,
    }
    d = b["larger-delays"].network_fields(delayed=True)
    assert d["delay_scale"] == 3.0 and d["max_delay_scale"] == 3.0
    assert (
        b["link-loss"].network_fields(delayed=True)["max_delay_scale"] == 3.0
    )  # one buffer for all cases
    with pytest.raises(BatteryError, match="larger_delays needs a network with delays"):
        b["larger-delays"].network_fields(delayed=False)
    assert not b["link-loss"].applies_to(network=False)
    assert b["link-loss"].applies_to(network=True)
    assert not b["larger-delays"].applies_to(network=True, delayed=False)
    assert b["outage"].applies_to(network=False)


@pytest.mark.parametrize(
    "scenario, delayed",
    [("compose-li2020-on-cw", False), ("compose-li2020-delays-on-yang2013", True)],
)
def test_every_case_builds_one_program_structure(scenario, delayed):
    """Each case's fields make a valid composed scenario, and all cases of one method (both actuator
    levels) have one compile key: the league runs them in one compiled program."""
    path = Path(ftc.__file__).parent / "scenarios" / f"{scenario}.toml"
    base = tomllib.loads(path.read_text())
    base["simulation"].update(horizon=1.0, record_every=1)
    base["metrics"] = []
    keys = set()
    for case in load_battery("v1"):
        if not case.applies_to(network=True, delayed=delayed):
            continue
        for sat in (None, 0.2):
            raw = dict(
                base,
                actuator={"type": "fault-battery", **case.actuator_fields(saturation=sat)},
                network={**base["network"], **case.network_fields(delayed=delayed)},
            )
            keys.add(structure_key(make_loop(ftc.load_scenario(raw))))
    assert len(keys) == 1
