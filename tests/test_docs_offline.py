"""The documentation site works opened from disk (issue 45): it loads nothing remote and its search
works from ``file://``.

``make docs`` itself fails when a built page loads a remote resource (the hook
``docs/hooks/offline_check.py`` runs after every build); here the scanner is tested on hand-made pages,
and -- when a built ``site/`` is there (``make docs``; CI builds it after the tests, so these two are
skipped there) -- the site is scanned and its search is run in headless Chromium with every host name
unresolvable, so that any request to the network fails and shows.
"""

from __future__ import annotations

import html
import importlib.util
import json
import re
import shutil
import subprocess
import sys
import types
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SITE = ROOT / "site"


@pytest.fixture(scope="module")
def check():
    spec = importlib.util.spec_from_file_location(
        "offline_check", ROOT / "docs" / "hooks" / "offline_check.py"
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_scanner_finds_every_kind_of_remote_load(check):
    page = """<html><head>
    <link rel="stylesheet" href="https://fonts.googleapis.com/css?family=Roboto">
    <link rel="preconnect" href="//fonts.gstatic.com">
    <script src="https://unpkg.com/iframe-worker/shim"></script>
    <style>@import "https://x.org/a.css"; body { background: url( 'http://x.org/b.png' ) }</style>
    </head><body style="background-image:url(https://x.org/c.png)">
    <img src="assets/local.png" srcset="a.png 1x, https://x.org/d.png 2x">
    <iframe src="https://x.org/e"></iframe>
    <a href="https://keepachangelog.com/">a link is navigation, not a load</a>
    <img src="data:image/png;base64,AAAA"><script src="assets/javascripts/bundle.js"></script>
    </body></html>"""
    found = check.html_remote_loads(page)
    for needle in (
        "fonts.googleapis.com",
        "//fonts.gstatic.com",
        "unpkg.com",
        "x.org/a.css",
        "x.org/b.png",
        "x.org/c.png",
        "x.org/d.png",
        "x.org/e",
    ):
        assert sum(needle in f for f in found) == 1, (needle, found)
    assert len(found) == 8 and not any("keepachangelog" in f or "data:" in f for f in found)
    assert check.css_remote_urls('@import url("https://x.org/f.css"); a{b:url(local.svg)}') == [
        "https://x.org/f.css"
    ]


def test_a_remote_load_fails_the_build(check, tmp_path, monkeypatch):
    try:
        from mkdocs.exceptions import PluginError
    except (
        ModuleNotFoundError
    ):  # `make test` runs without the docs extra (CI installs it for `make docs`)
        PluginError = type("PluginError", (Exception,), {})
        exceptions = types.ModuleType("mkdocs.exceptions")
        exceptions.PluginError = PluginError
        monkeypatch.setitem(sys.modules, "mkdocs", types.ModuleType("mkdocs"))
        monkeypatch.setitem(sys.modules, "mkdocs.exceptions", exceptions)

    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "page.html").write_text('<script src="https://cdn.example/m.js"></script>')
    (tmp_path / "style.css").write_text("a { background: url(local.png) }")
    with pytest.raises(
        PluginError, match=r"(?s)1 remote resource.*sub/page.html: <script src=https"
    ):
        check.on_post_build({"site_dir": str(tmp_path)})
    (tmp_path / "sub" / "page.html").write_text('<script src="../m.js"></script>')
    check.on_post_build({"site_dir": str(tmp_path)})  # nothing remote: passes


needs_site = pytest.mark.skipif(
    not (SITE / "index.html").is_file(), reason="no built site/ (make docs builds it)"
)


@needs_site
def test_built_site_loads_nothing_remote(check):
    assert check.remote_loads(SITE) == []
    assert (SITE / "search" / "search_index.js").is_file()  # the offline plugin's index for file://


_SEARCH_PROBE = """<script>(function () {
  var errors = [];
  window.addEventListener("error", function (ev) { var t = ev.target;
    errors.push(t && t !== window && t.tagName ? "resource: " + (t.src || t.href) : "uncaught: " + ev.message);
  }, true);
  window.addEventListener("load", function () { setTimeout(function () {
    var input = document.querySelector("input.md-search__input");
    input.focus(); input.value = "QUERY";
    ["focus", "input", "keyup"].forEach(function (k) { input.dispatchEvent(new Event(k, {bubbles: true})); });
    setTimeout(function () {
      var p = document.createElement("pre"); p.id = "__probe";
      p.textContent = JSON.stringify({errors: errors,
        results: Array.prototype.map.call(document.querySelectorAll(".md-search-result__item a"),
                                          function (a) { return a.href; }),
        loaded: performance.getEntriesByType("resource").map(function (e) { return e.name; })});
      document.body.appendChild(p);
    }, 3000); }, 1000); });
})();</script>"""


@needs_site
@pytest.mark.skipif(shutil.which("chromium") is None, reason="headless Chromium not found")
def test_built_site_searches_from_disk_without_network(tmp_path):
    probe = SITE / "__search_probe.html"
    text = (SITE / "index.html").read_text(encoding="utf-8")
    probe.write_text(
        text.replace("<head>", "<head>" + _SEARCH_PROBE.replace("QUERY", "fault battery"), 1),
        encoding="utf-8",
    )
    try:
        proc = subprocess.run(
            [
                shutil.which("chromium"),
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                f"--user-data-dir={tmp_path / 'profile'}",
                "--host-resolver-rules=MAP * ~NOTFOUND",  # any network request fails
                "--window-size=1280,900",
                "--virtual-time-budget=15000",
                "--dump-dom",
                probe.as_uri(),
            ],
            capture_output=True,
            text=True,
            timeout=120,
        )
    finally:
        probe.unlink()
    match = re.search(r'<pre id="__probe">(.*?)</pre>', proc.stdout, re.S)
    assert match, proc.stderr[-2000:]
    got = json.loads(html.unescape(match.group(1)))
    assert got["errors"] == [] and all(u.startswith("file:") for u in got["loaded"]), got
    assert any("/league.html" in u for u in got["results"]), got["results"]
