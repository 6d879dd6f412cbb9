"""The declared-study runner (``papers/_study.py``): rows, notes and summary filled from the quantities,
verdicts computed from the basis, clear errors for a name the quantities do not hold."""

from __future__ import annotations

import pytest

from formation_ftc.papers import _study

DATA = {
    "reproduction": {
        "runs": ["a"],
        "summary": ["x"],
        "notes": ["x is {x:.2f}"],
        "seeds": [3],
    },
    "rows": [
        {
            "quantity": "x small",
            "published": "1 (Eq. {1})",
            "ours": "{x:.3f}",
            "criterion": "<= {limit}",
            "basis": [["<=", "x", "limit"]],
        },
        {"quantity": "y", "published": "", "ours": "{y[k]}", "criterion": "none"},
        {"quantity": "hidden", "published": "", "ours": "", "criterion": "", "when": "never"},
        {
            "quantity": "x tight",
            "published": "",
            "ours": "{x}",
            "criterion": "",
            "basis": [["abs<=", "x", 1.0, 0.01]],
        },
    ],
}


@pytest.fixture
def no_runs(monkeypatch):
    monkeypatch.setattr(_study, "load_runs", lambda spec, overrides=None, values=None: {"a": None})


def _quantities(runs, constants):
    assert set(runs) == {"a"}
    return {"x": 1.5, "limit": 2.0, "y": {"k": "text"}, "never": False}


def test_rows_notes_and_summary_come_from_the_quantities(no_runs, tmp_path):
    report = _study.run_study("demo", _quantities, tmp_path, data=DATA)
    rows = {r.quantity: r for r in report.rows}
    assert set(rows) == {"x small", "y", "x tight"}  # "hidden": its `when` is false
    assert rows["x small"].ours == "1.500" and rows["x small"].criterion == "<= 2.0"
    assert rows["x small"].published == "1 (Eq. {1})"  # the paper's text is never filled
    assert rows["x small"].verdict == "match" and rows["x small"].basis == (("<=", 1.5, 2.0),)
    assert rows["x tight"].verdict == "differs"  # |1.5 - 1| > 0.01
    assert rows["y"].verdict == "not stated" and rows["y"].ours == "text"
    assert report.notes == ["x is 1.50"] and report.summary == {"x": 1.5} and report.seeds == [3]


def test_a_name_the_quantities_do_not_hold_is_a_clear_error(no_runs, tmp_path):
    data = {**DATA, "rows": [{**DATA["rows"][0], "basis": [["<=", "x", "nope"]]}]}
    with pytest.raises(ValueError, match=r"row 'x small': no quantity 'nope' \(known: a?.*limit"):
        _study.run_study("demo", _quantities, tmp_path, data=data)
    data = {**DATA, "rows": [{**DATA["rows"][0], "ours": "{z:.2f}"}]}
    with pytest.raises(ValueError, match=r"row 'x small': '\{z:.2f\}' cannot be filled"):
        _study.run_study("demo", _quantities, tmp_path, data=data)


def test_a_row_for_each_item_and_a_basis_held_by_a_quantity(no_runs, tmp_path):
    rows = [
        {
            "quantity": "{name}: small",
            "published": "Fig. {fig}",
            "ours": "{value:.1f}",
            "criterion": "< {limit}",
            "basis": "clauses",
            "for_each": "items",
        }
    ]

    def quantities(runs, constants):
        items = [
            {"name": n, "fig": f, "value": v, "clauses": (("<", v, 2.0),)}
            for n, f, v in (("a", 4, 1.0), ("b", 5, 3.0))
        ]
        return {"items": items, "limit": 2.0}

    data = {"reproduction": {"runs": ["a"]}, "rows": rows}
    report = _study.run_study("demo", quantities, tmp_path, data=data)
    got = [(r.quantity, r.published, r.ours, r.verdict) for r in report.rows]
    assert got == [("a: small", "Fig. 4", "1.0", "match"), ("b: small", "Fig. 5", "3.0", "differs")]
