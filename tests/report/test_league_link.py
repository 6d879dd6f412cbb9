"""The reproduction report links league leaderboards (given with --league, or found in the report
directory) with a relative link and the top of each ranking."""

from __future__ import annotations

import json
from pathlib import Path

from formation_ftc.report import html as html_report


def _league(d: Path, name: str) -> Path:
    (d / "leaderboard").mkdir(parents=True)
    (d / "leaderboard" / "index.html").write_text("<html></html>")
    board = {
        "league": name,
        "seeds": 10,
        "requirement": {"metric": "rms_shape_error"},
        "ranking": {
            "unsaturated": [
                {"method": "azizi2009"},
                {"method": "sir-ftc"},
                {"method": "li2020-thm1"},
                {"method": "lqr"},
            ]
        },
    }
    (d / "leaderboard" / "leaderboard.json").write_text(json.dumps(board))
    return d


def test_given_and_found_leagues_are_linked(tmp_path):
    out = tmp_path / "report"
    out.mkdir()
    given = _league(tmp_path / "elsewhere" / "lg", "translational")
    _league(out / "att", "attitude")
    page = html_report.render_index([], out, {}, leagues=[given])
    assert 'href="../elsewhere/lg/leaderboard/index.html"' in page
    assert 'href="att/leaderboard/index.html"' in page
    assert (
        "azizi2009, sir-ftc, li2020-thm1" in page
        and "lqr" not in page.split("league translational")[1][:200]
    )
    # nothing to link: no section
    assert "FTC league leaderboards" not in html_report.render_index([], tmp_path / "empty", {})
