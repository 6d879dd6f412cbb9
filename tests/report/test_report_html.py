"""HTML page generation and provenance (no browser here; see test_report_chromium.py).

Truths: the bytes of the PNGs the fakes write (base64 round trip), the entries' own content, HTML
escaping of every text field, and -- for the git commit -- the .git directory read directly.
"""

from __future__ import annotations

import base64
import io
import json
import re
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest
from report_fakes import failing_reproduction, ok_reproduction
from rich.console import Console

from formation_ftc.report import html as rh
from formation_ftc.report import metadata
from formation_ftc.report.reproduce import reproduce


class _Collector(HTMLParser):
    """Collects tag attributes and the ids/classes the tests look for."""

    def __init__(self) -> None:
        super().__init__()
        self.tags: list[tuple[str, dict]] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))

    def find(self, tag: str, class_: str | None = None, **attrs) -> list[dict]:
        out = []
        for t, a in self.tags:
            if t != tag or (class_ and class_ not in (a.get("class") or "").split()):
                continue
            if all(a.get(k) == v for k, v in attrs.items()):
                out.append(a)
        return out


def _parse(text: str) -> _Collector:
    c = _Collector()
    c.feed(text)
    return c


def _make(tmp_path, avail, **kw):
    out = tmp_path / "rep"
    reproduce(
        list(kw.pop("papers", ["all"])),
        out,
        progress=False,
        available=avail,
        console=Console(file=io.StringIO()),
        **kw,
    )
    return out, (out / "index.html").read_text()


def test_sections_tables_and_embedded_figures(tmp_path):
    avail = {
        "alpha": ok_reproduction("alpha"),
        "broken": failing_reproduction("broken", "nan in <state>"),
    }
    out, page = _make(tmp_path, avail, include_3d=False)
    doc = _parse(page)
    sections = doc.find("section", class_="paper")
    assert [s["data-paper"] for s in sections] == ["alpha", "broken"]
    assert [s["data-status"] for s in sections] == ["ok", "failed"]
    assert [s["id"] for s in sections] == ["paper-alpha", "paper-broken"]
    # figures: embedded as data URIs whose bytes are exactly the files the reproduction wrote
    imgs = doc.find("img", class_="figure-img")
    assert len(imgs) == 2
    for img, name in zip(imgs, ["fig3.png", "fig4.png"], strict=True):
        prefix = "data:image/png;base64,"
        assert img["src"].startswith(prefix)
        assert base64.b64decode(img["src"][len(prefix) :]) == (out / "alpha" / name).read_bytes()
    # verdict colouring classes, one row per ComparisonRow
    rows = [
        a.get("class")
        for t, a in doc.tags
        if t == "tr" and (a.get("class") or "").startswith("verdict-")
    ]
    assert rows == ["verdict-match", "verdict-differs", "verdict-not-stated"]
    holds = [
        a.get("class")
        for t, a in doc.tags
        if t == "tr" and (a.get("class") or "").startswith("holds-")
    ]
    assert holds == ["holds-yes", "holds-no", "holds-na"]
    # errata, seeds, notes, wall time, failure traceback (escaped), provenance
    assert "E001-01" in page and "alpha: sign of eq. (7) corrected" in page
    assert "<dt>seeds</dt><dd>7, 8</dd>" in page and "alpha note" in page
    assert "RuntimeError: nan in &lt;state&gt;" in page and "Traceback" in page
    assert 'id="run-metadata"' in page and "version_" not in page and ">jax<" in page
    # text fields are escaped, never interpreted as markup
    assert "&lt;x_i&gt; &amp; velocities" in page and "<x_i>" not in page
    assert "&lt;em&gt;escaped&lt;/em&gt;" in page and "<em>" not in page


def test_page_is_self_contained(tmp_path):
    """Nothing is loaded from the network: every src/href is a data URI, an in-page anchor or a file
    of the report tree (plotly's bundle, when a 3-D view is drawn)."""
    avail = {"alpha": ok_reproduction("alpha", trajectory=True)}
    out, page = _make(tmp_path, avail, include_3d=rh.plotly_available())
    doc = _parse(page)
    refs = [
        (t, a.get("src") or a.get("href")) for t, a in doc.tags if a.get("src") or a.get("href")
    ]
    assert refs, "expected images and anchors"
    for tag, ref in refs:
        local = not re.match(r"^[a-z]+:|^//|^/", ref) and (out / ref).resolve().is_file()
        assert ref.startswith("data:") or ref.startswith("#") or local, (tag, ref[:80])
    assert not doc.find("link") and not doc.find("iframe")
    assert not re.search(r"url\(\s*['\"]?https?:", page.split("</style>")[0])


def _plotly_copies(tree: Path) -> list[Path]:
    return sorted(tree.rglob("plotly*.js"))


def test_trajectory_view_with_plotly(tmp_path):
    from plotly.offline import get_plotlyjs

    avail = {
        "alpha": ok_reproduction("alpha", trajectory=True),
        "beta": ok_reproduction("beta", trajectory=True),
    }
    out, page = _make(tmp_path, avail)
    # one copy of plotly's bundle for the whole report tree, at its root, loaded once by the page
    assert _plotly_copies(out) == [out / "plotly.min.js"]
    assert (out / "plotly.min.js").read_text(encoding="utf-8") == get_plotlyjs()
    assert _parse(page).find("script", src="plotly.min.js") and get_plotlyjs() not in page
    assert page.count("Plotly.newPlot(") == 2
    assert 'id="paper-alpha-traj3d-1"' in page and 'id="paper-beta-traj3d-1"' in page
    assert "alpha formation (LVLH)" in page
    # no trajectory file -> no plotly bundle at all (keeps report trees small)
    out2, page2 = _make(tmp_path / "b", {"alpha": ok_reproduction("alpha")})
    assert "Plotly.newPlot(" not in page2 and "<script" not in page2
    assert _plotly_copies(out2) == []


def test_a_tree_shares_one_plotly_copy(tmp_path):
    """A report written inside a tree that already holds this plotly's bundle links that copy; a
    stale copy of another plotly version is not used."""
    from plotly.offline import get_plotlyjs

    tree = tmp_path / "tree"
    tree.mkdir()
    (tree / "plotly.min.js").write_text(get_plotlyjs(), encoding="utf-8")
    assert rh.plotly_script(tree / "a" / "b") == "../../plotly.min.js"
    assert _plotly_copies(tree) == [tree / "plotly.min.js"]
    (tree / "plotly.min.js").write_text("/* plotly.js v0.0.1 */", encoding="utf-8")
    assert rh.plotly_script(tree / "a", root=tree) == "../plotly.min.js"
    assert (tree / "plotly.min.js").read_text(encoding="utf-8") == get_plotlyjs()  # replaced


def test_trajectory_view_without_plotly_or_disabled(tmp_path, monkeypatch):
    avail = {"alpha": ok_reproduction("alpha", trajectory=True)}
    _, page = _make(tmp_path / "off", avail, include_3d=False)
    assert "3-D view left out (--no-3d)" in page and "Plotly.newPlot(" not in page
    monkeypatch.setattr(rh, "plotly_available", lambda: False)
    _, page = _make(tmp_path / "missing", avail)
    assert "Interactive 3-D view unavailable: plotly is not installed" in page
    assert "Plotly.newPlot(" not in page
    assert len(_parse(page).find("img", class_="figure-img")) == 2  # the rest still works


def test_write_and_load_trajectory3d(tmp_path):
    t = np.linspace(0.0, 1.0, 5001)
    pos = np.c_[t, 2 * t, 3 * t]
    path = rh.write_trajectory3d(tmp_path, {"SC1": pos}, title="one", max_points=100)
    data = json.loads(path.read_text())
    pts = data["spacecraft"]["SC1"]
    assert len(pts) == 100 and pts[0] == [0.0, 0.0, 0.0] and pts[-1] == [1.0, 2.0, 3.0]  # ends kept
    rh.write_trajectory3d(tmp_path, {"SC2": pos[:10]}, title="two")  # appends a second view
    views, problems = rh.load_trajectories(path)
    assert [v["title"] for v in views] == ["one", "two"] and problems == []
    with pytest.raises(ValueError, match=r"shape \(n, 3\)"):
        rh.write_trajectory3d(tmp_path, {"SC1": np.zeros((4, 2))})
    bad = tmp_path / "bad.json"
    bad.write_text(
        json.dumps(
            {
                "title": "x",
                "spacecraft": {"A": [[0, 0, 0], [1, 1, 1]], "B": [[0, 0]], "C": [[0, 0, "nan"]]},
            }
        )
    )
    views, problems = rh.load_trajectories(bad)
    assert list(views[0]["spacecraft"]) == ["A"] and len(problems) == 2
    bad.write_text("{not json")
    assert rh.load_trajectories(bad)[0] == []


def test_render_index_from_minimal_entries(tmp_path):
    """The page tolerates sparse entries (e.g. a report.json written by an older version)."""
    page = rh.render_index([{"paper": "x y", "status": "ok"}], tmp_path, {"git_commit": "abc"})
    doc = _parse(page)
    assert [s["id"] for s in doc.find("section", class_="paper")] == ["paper-x-y"]
    assert "No figures." in page and "No conditions declared." in page and "commit abc" in page


# ------------------------------------------------------------------------------------ metadata
def _head_from_git_dir(repo: Path) -> str | None:
    """HEAD read from the .git directory without running git (independent of git_commit())."""
    git = repo / ".git"
    if not (git / "HEAD").is_file():
        return None
    head = (git / "HEAD").read_text().strip()
    if not head.startswith("ref: "):
        return head
    ref = head[5:]
    if (git / ref).is_file():
        return (git / ref).read_text().strip()
    packed = git / "packed-refs"
    if packed.is_file():
        for line in packed.read_text().splitlines():
            if line.endswith(" " + ref):
                return line.split()[0]
    return None


def test_provenance_fields():
    prov = metadata.provenance()
    assert all(isinstance(k, str) and isinstance(v, str) for k, v in prov.items())
    for key in (
        "git_commit",
        "python",
        "platform",
        "created_utc",
        "jax_backend",
        "version_jax",
        "version_numpy",
        "version_scipy",
        "version_xarray",
        "version_plotly",
        "version_formation-ftc",
    ):
        assert key in prov, key
    import numpy

    assert prov["version_numpy"] == numpy.__version__
    import platform

    assert prov["python"] == platform.python_version()
    repo = Path(metadata.__file__).resolve().parents[3]
    head = _head_from_git_dir(repo)
    commit = prov["git_commit"]
    if head is None:
        assert commit == "unknown" or re.fullmatch(r"[0-9a-f]{40}(\+dirty)?", commit)
    else:
        assert commit.split("+")[0] == head


def test_git_commit_unknown_outside_a_checkout(monkeypatch):
    from formation_ftc import provenance as base

    def no_git(*a, **k):
        raise FileNotFoundError("git")

    base.git_commit.cache_clear()
    monkeypatch.setattr(subprocess, "run", no_git)
    try:
        assert metadata.git_commit() == "unknown"
    finally:
        monkeypatch.undo()
        base.git_commit.cache_clear()
