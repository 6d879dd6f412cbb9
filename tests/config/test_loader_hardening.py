"""Strict loading: exact --set values and list indices, booleans never numbers, finite floats,
bounded seeds and nesting, unreadable or non-UTF-8 files named -- all as ScenarioError."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from formation_ftc.api import load_scenario
from formation_ftc.config.base import MAX_SEED, SimulationSection
from formation_ftc.config.loader import ScenarioError, parse_override, set_dotted
from formation_ftc.errors import InputError


@pytest.mark.parametrize(
    "text,expected",
    [
        ("a.b=1.5", ("a.b", 1.5)),
        ("a.b = [1, 2]", ("a.b", [1, 2])),
        ("a.b=true", ("a.b", True)),
        ("f=1 - 0.1*t", ("f", "1 - 0.1*t")),  # not TOML: an expression string
        ("f=where(i==2, 0.5, 1)", ("f", "where(i==2, 0.5, 1)")),
        ('s="quoted # not a comment"', ("s", "quoted # not a comment")),
    ],
)
def test_override_values(text, expected):
    assert parse_override(text) == expected


@pytest.mark.parametrize(
    "text,fragment",
    [
        ("a=1\nb=2", "single TOML value on one line"),
        ("a=1\rb=2", "single TOML value"),
        ("a=[1, 2", "invalid TOML value"),
        ("a={x = 1", "invalid TOML value"),
        ('a="open', "invalid TOML value"),
        ("a=", "empty value"),
        ("=1", "empty dotted path"),
        ("novalue", "must look like dotted.path=value"),
    ],
)
def test_bad_override_values(text, fragment):
    with pytest.raises(ScenarioError, match=fragment):
        parse_override(text)


def test_set_dotted_indices_and_scalars():
    raw = {"s": {"mass": [1.0, 2.0], "name": "x"}}
    set_dotted(raw, "s.mass.1", 5.0)
    set_dotted(raw, "s.new.deep", 3)  # missing tables are created
    assert raw["s"]["mass"] == [1.0, 5.0] and raw["s"]["new"] == {"deep": 3}
    for path, fragment in [
        ("s.mass.2", "index 2 is out of range; the list has 2"),
        ("s.mass.-1", "non-negative integer"),
        ("s.mass.x", "non-negative integer"),
        ("s.mass.0.x", "s.mass.0 is a number"),
        ("s.name.x", "s.name is a str"),
        ("s..x", "empty part"),
    ]:
        with pytest.raises(ScenarioError, match=fragment):
            set_dotted(raw, path, 1)
    assert raw["s"]["mass"] == [1.0, 5.0]


def test_booleans_infinities_and_seed_bounds_at_model_level():
    with pytest.raises(ValidationError, match="booleans are not numbers"):
        SimulationSection(horizon=True, dt=0.1)
    with pytest.raises(ValidationError, match="finite number"):
        SimulationSection(horizon=float("inf"), dt=0.1)
    SimulationSection(horizon=1.0, dt=0.1, seed=MAX_SEED)
    with pytest.raises(ValidationError, match="less than or equal to 4294967295"):
        SimulationSection(horizon=1.0, dt=0.1, seed=MAX_SEED + 1)


def test_boolean_fields_still_accept_booleans():
    from formation_ftc.registry import methods

    for method in methods().values():
        assert method.schema.model_json_schema()  # every schema builds with the strict base
    for flag in (True, False):
        scn = load_scenario("yang2013-healthy", {"simulation.horizon": 2.0})
        raw = scn.model_dump(mode="json")
        bool_paths = _bool_fields(raw)
        assert bool_paths, "yang2013 has boolean fields"
        for path in bool_paths:
            assert load_scenario("yang2013-healthy", [f"{path}={str(flag).lower()}"]) is not None


def _bool_fields(d, prefix=""):
    out = []
    for k, v in d.items():
        p = f"{prefix}.{k}" if prefix else k
        if isinstance(v, bool):
            out.append(p)
        elif isinstance(v, dict):
            out += _bool_fields(v, p)
    return out


def test_errors_are_input_errors_naming_the_file(tmp_path):
    bad = tmp_path / "x.toml"
    bad.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(InputError, match=rf"scenario file '{bad}' is not UTF-8 text"):
        load_scenario(bad)
    deep = tmp_path / "deep.toml"
    deep.write_text("a = " + "{b = " * 40 + "1" + "}" * 40 + "\n")
    with pytest.raises(ScenarioError, match=rf"{deep}: TOML nested more than 32 levels"):
        load_scenario(deep)
    nested = {"scenario": {"method": "composed"}}
    node = nested
    for _ in range(2000):  # a dict nested beyond the stack: refused before any recursion
        node["x"] = {}
        node = node["x"]
    with pytest.raises(ScenarioError, match="nested more than 32 levels"):
        load_scenario(nested)


def test_unusable_paths_and_huge_files(tmp_path):
    with pytest.raises(ScenarioError, match="invalid scenario path 'aaaa.*File name too long"):
        load_scenario("a" * 5000)
    big = tmp_path / "big.toml"
    with open(big, "wb") as f:
        f.truncate(17 * 2**20)  # sparse: costs no disk
    with pytest.raises(ScenarioError, match="is 17 MiB; at most 16 MiB"):
        load_scenario(big)
    import os

    fifo = tmp_path / "fifo.toml"
    os.mkfifo(fifo)  # reading it would block: refused as not a regular file
    with pytest.raises(ScenarioError, match="is not a regular file"):
        load_scenario(fifo)
