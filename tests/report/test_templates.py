"""The three HTML pages (run page, reproduction report, league leaderboard) come from Jinja2 templates
with one base and one style sheet, and escape every value (issue 45 item 7)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import xarray as xr

import formation_ftc
from formation_ftc.report import html as rh
from formation_ftc.report.run_page import write_run_page
from formation_ftc.report.templating import render

PACKAGE = Path(formation_ftc.__file__).resolve().parent
STYLE = (PACKAGE / "report" / "templates" / "style.css").read_text(encoding="utf-8")


def _style(page: str) -> str:
    return re.search(r"<style>\n(.*?)</style>", page, re.S).group(1).strip()


def _league_page() -> str:
    from test_league_page import _board  # tests/league (importable: rootdir conftest)

    return _board()[1]


def test_one_style_sheet_for_every_page(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(Path(__file__).resolve().parents[1] / "league"))
    ds = xr.Dataset(attrs={"scenario_name": "s"})
    run = write_run_page(tmp_path, ds, {"x": 1.0}, []).read_text()
    report = rh.render_index([{"paper": "p", "status": "ok"}], tmp_path, {})
    league = _league_page()
    for page in (run, report, league):
        assert _style(page) == STYLE.strip()
        assert page.startswith("<!DOCTYPE html>") and '<header class="top"><h1>' in page


def test_values_are_escaped(tmp_path):
    page = render("base.html.j2", title="<script>x</script>", subtitle="a & b")
    assert "<script>x" not in page and "&lt;script&gt;x&lt;/script&gt;" in page
    assert "a &amp; b" in page
    ds = xr.Dataset(
        {"position": (("time",), np.zeros(2))},
        coords={"time": [0.0, 1.0]},
        attrs={"scenario_name": "<b>n</b>", "title": "t & u", "method": "</script><i>"},
    )
    page = write_run_page(tmp_path, ds, {"<m>": 1.0}, ["fig <1>.png"]).read_text()
    assert "<b>n</b>" not in page and "&lt;b&gt;n&lt;/b&gt;" in page and "&lt;m&gt;" in page
    # the metadata JSON cannot end its script element early
    assert re.search(r'id="run-metadata">[^<]*</script>', page)


def test_no_html_left_in_the_python_code():
    sources = [*sorted((PACKAGE / "report").glob("*.py")), PACKAGE / "league" / "report.py"]
    for path in sources:
        text = path.read_text(encoding="utf-8")
        assert not re.search(r"<(table|tr|td|th|section|h[1-6]|html|body|style)\b", text), path.name
