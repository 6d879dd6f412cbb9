"""Jupyter display of the API's result objects (``_repr_html_``) and their ``__repr__``: the HTML is well
formed (every element closed, checked with the standard library's parser), shows what the object holds
(read from the object itself, never from the renderer), and shows user text as text (escaped).

No simulation runs here: the objects are loaded, checked or built directly.
"""

from __future__ import annotations

import json
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from formation_ftc import api
from formation_ftc.campaign.runner import CampaignOutcome
from formation_ftc.registry import Condition

VOID = {"br", "hr", "img", "meta", "link", "input", "col", "wbr"}
HOSTILE = "<script>alert('x')</script> & \"quotes\""


class _Checked(HTMLParser):
    """Parses an HTML fragment: every element closed in order; collects the text and the table cells."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.stack: list[str] = []
        self.tags: list[str] = []
        self.text: list[str] = []
        self.cells: list[list[str]] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        if tag == "tr":
            self.cells.append([])
        if tag in ("td", "th"):
            self.cells[-1].append("")
        if tag not in VOID:
            self.stack.append(tag)

    def handle_endtag(self, tag):
        assert self.stack and self.stack[-1] == tag, f"</{tag}> closes {self.stack[-1:]}"
        self.stack.pop()

    def handle_data(self, data):
        self.text.append(data)
        if self.stack and self.stack[-1] in ("td", "th"):
            self.cells[-1][-1] += data


def _parse(html: str) -> _Checked:
    p = _Checked()
    p.feed(html)
    p.close()
    assert p.stack == [], f"unclosed elements {p.stack}"
    assert "script" not in p.tags  # user text never becomes markup
    return p


def _row(p: _Checked, first: str) -> list[str]:
    return next(r for r in p.cells if r and r[0].strip() == first)


def test_scenario_card():
    scn = api.load_scenario(
        "cw-pd-fault", {"scenario.description": HOSTILE, "simulation.horizon": 300.0}, build=False
    )
    p = _parse(scn._repr_html_())
    text = "".join(p.text)
    assert scn.scenario.name in text and HOSTILE in text  # shown as the text it is
    assert _row(p, "method")[1] == scn.scenario.method
    assert _row(p, "horizon")[1] == "300 s"
    assert _row(p, "step")[1].startswith(
        f"{scn.simulation.dt:g} s ({scn.simulation.n_steps:,} steps"
    )
    assert _row(p, "seed")[1] == str(scn.simulation.seed)
    raw = scn.model_dump(mode="json")
    for slot in ("plant", "controller", "sensors", "actuator"):
        assert _row(p, slot)[1] == raw[slot]["type"]
    line = repr(scn)
    assert "\n" not in line and repr(scn.scenario.name) in line and "300 s" in line


def test_conditions_table_and_check():
    conds = api.Conditions(
        [
            Condition("rank <full>", "Thm 1", "r = 6", "r = 6", True, basis="exact"),
            Condition("gain", "eq. (3)", "k = 0.2", "k > 0.5 & k < 9", False, basis="exact"),
            Condition("sampled bound", "Lemma 2", "max = 0.1", "< 1", None, basis="sampled"),
            Condition("note", "-", "T = 2 s", "-", None, required=False, basis="informative"),
        ]
    )
    p = _parse(conds._repr_html_())
    rows = [r for r in p.cells if r and r[0] != "condition"]
    assert [r[0] for r in rows] == [c.name for c in conds]  # "<full>" as text
    assert [r[4] for r in rows] == ["yes", "NO", "unproven", "n/a"]
    assert rows[1][3] == "k > 0.5 & k < 9"
    assert "gain" in "".join(p.text).split("failing:")[-1]
    text = repr(conds)
    assert text.splitlines()[0] == "Conditions (4)" and all(c.name in text for c in conds)
    assert conds == list(conds) and isinstance(conds, list)

    checked = api.check("cw-pd-fault")
    assert isinstance(checked, api.Conditions) and len(checked) > 0
    rows = [r for r in _parse(checked._repr_html_()).cells if r and r[0] != "condition"]
    assert [r[0] for r in rows] == [c.name for c in checked]


def test_metrics_table():
    m = api.Metrics(
        {"delta_v_total": 0.012345678, "<odd>": float("nan")}, {"delta_v_total": "m s-1"}
    )
    p = _parse(m._repr_html_())
    assert _row(p, "delta_v_total")[1:] == ["0.01235", "m s-1"]
    assert _row(p, "<odd>")[1] == "nan"
    assert json.loads(json.dumps(m))["delta_v_total"] == 0.012345678  # a plain dict to any code
    assert m.units == {"delta_v_total": "m s-1"}


def test_campaign_outcome_card():
    rng = np.random.default_rng(3)
    err = rng.uniform(0.0, 2.0, 40)
    err[:3] = np.nan  # failed runs
    results = pd.DataFrame(
        {
            "run_id": np.arange(40),
            "status": ["failed"] * 3 + ["ok"] * 37,
            "metric:max_position_error": err,
        }
    )
    outcome = CampaignOutcome(
        Path("out/<c>"),
        40,
        3,
        4,
        3,
        1,
        8.0,
        results,
        "local (in-process)",
        name="<tiny>",
        n_planned=40,
        n_computed=30,
        n_diverged=3,
        units={"metric:max_position_error": "m"},
    )
    assert outcome.rate == pytest.approx(30 / 8.0) and outcome.n_kept == 10
    p = _parse(outcome._repr_html_())
    text = "".join(p.text)
    assert "<tiny>" in text and "out/<c>" in text
    assert _row(p, "runs")[1] == "40 (37 ok, 3 failed)"
    assert _row(p, "wall time")[1] == "8 s, 3.75 runs/s"
    name, finite, median, spread, units = _row(p, "max_position_error")
    ok = err[np.isfinite(err)]
    assert finite == "37" and units == "m"
    assert median == f"{np.median(ok):.4g} m"
    assert spread == f"{np.percentile(ok, 5):.4g} .. {np.percentile(ok, 95):.4g}"
    assert "\n" not in repr(outcome) and "3.75 runs/s" in repr(outcome)
    assert "3.75 runs/s" in str(outcome)


def test_result_dataset_variables_carry_units_and_long_names():
    """xarray draws the run dataset itself: its variables must carry units and long_name (cf.apply_cf)."""
    from formation_ftc.cf import apply_cf, cf_problems
    from formation_ftc.components.controllers.none import ZeroController
    from formation_ftc.components.plants.clohessy_wiltshire import ClohessyWiltshirePlant
    from formation_ftc.sim.loop import ClosedLoop
    from formation_ftc.sim.records import records_to_dataset

    plant = ClohessyWiltshirePlant(
        mean_motion=np.float64(1e-3),
        mass=np.array([10.0, 12.0]),
        initial_state_lvlh=np.zeros((2, 6)),
    )
    loop = ClosedLoop(plant=plant, controller=ZeroController(count=2), dt=10.0, n_steps=2)
    ds = records_to_dataset(
        loop, {"position": np.ones((3, 2, 3)), "velocity": np.zeros((3, 2, 3))}, n_records=3
    )
    apply_cf(ds, scenario_name="t", method="composed")
    assert cf_problems(ds) == []
    html = ds._repr_html_()
    for name in ds.variables:
        assert ds[name].attrs["units"] and ds[name].attrs["long_name"]
        assert ds[name].attrs["long_name"] in html
