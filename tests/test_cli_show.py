"""``formation-ftc show`` prints arrays as TOML a person writes (issue 45): one line when it fits
(``x = [1.0, 2.0, 3.0]``, ``m = [[1, 0], [0, 1]]``), else one row or a few numbers per line -- never one
number per line -- and the printed TOML reads back (tomllib) to the resolved scenario, for every
built-in scenario, with and without the unit comments."""

from __future__ import annotations

import math
import re
import tomllib

import pytest

from formation_ftc.api import list_scenarios, load_scenario
from formation_ftc.cli import _toml_value, main

SCENARIOS = sorted(list_scenarios())
WIDTH = 100
_LONE_NUMBER = re.compile(r"^\s+[-+]?(\d[\d_.eE+-]*|inf|nan),$")


def _same(a, b) -> bool:
    """Equal, NaN equal to NaN, an int and a float never equal (TOML keeps the type)."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return type(a) is type(b) and a == b


@pytest.mark.parametrize("name", SCENARIOS)
def test_show_round_trips_and_writes_arrays_on_few_lines(name, capsys):
    resolved = load_scenario(name, build=False).model_dump(mode="json", exclude_none=True)
    assert main(["show", name, "--no-comments"]) == 0
    bare = capsys.readouterr().out
    assert main(["show", name]) == 0
    annotated = capsys.readouterr().out
    assert _same(tomllib.loads(bare), resolved) and _same(tomllib.loads(annotated), resolved)
    lines = bare.splitlines()
    assert not [ln for ln in lines if _LONE_NUMBER.match(ln)]  # the old one-number-per-line form
    # a line is longer than the width only when one string value alone is
    assert all(len(ln) <= WIDTH or re.search(r'"[^"]{40,}"', ln) for ln in lines)


def test_arrays_one_line_when_they_fit_else_wrapped():
    assert _toml_value([1.0, 2.0, 3.0]) == "[1.0, 2.0, 3.0]"
    assert _toml_value([[1, 0], [0, 1]]) == "[[1, 0], [0, 1]]"
    assert _toml_value([{"type": "x", "k": [1, 2]}]) == '[{ type = "x", k = [1, 2] }]'
    assert _toml_value([]) == "[]" and _toml_value([math.inf, -1e-10]) == "[inf, -1e-10]"
    long = [float(k) for k in range(60)]
    text = _toml_value(long)
    rows = text.splitlines()
    assert rows[0] == "[" and rows[-1] == "]" and 3 <= len(rows) - 2 <= 6
    assert all(len(r) <= WIDTH and r.startswith("    ") for r in rows[1:-1])
    matrix = [[float(k)] * 3 for k in range(40)]  # one row of the matrix per line
    rows = _toml_value(matrix).splitlines()
    assert rows[1] == "    [0.0, 0.0, 0.0]," and len(rows) == 42
    assert tomllib.loads(f"x = {_toml_value(matrix)}")["x"] == matrix
    assert tomllib.loads(f"x = {text}")["x"] == long
