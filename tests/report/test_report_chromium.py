"""Open the generated ``index.html`` in headless Chromium and check that it renders.

Issue 9: "A test opens index.html in headless Chromium and checks that the page renders every section
and image without console errors". The test installs nothing: it is skipped (with the reason) only
when the ``chromium`` binary (Debian package ``chromium``) is absent; CI installs it.

How: a copy of the page gets a probe script as the first thing in ``<head>``. It records every
``console.error``, uncaught exception, unhandled promise rejection and resource load error, and on
the ``load`` event writes into the DOM, as JSON, each section's id, size on screen and images, and
each image's decoded pixel size. ``chromium --headless --dump-dom`` prints the DOM after load; the
console messages Chromium logs on stderr (``--enable-logging=stderr``) are checked as well.
Truths: the pixel sizes of the PNGs the fakes wrote, the papers registered in the fakes.
"""

from __future__ import annotations

import html
import io
import json
import re
import shutil
import subprocess
from pathlib import Path

import pytest
from report_fakes import failing_reproduction, ok_reproduction
from rich.console import Console

from formation_ftc.report.html import plotly_available
from formation_ftc.report.reproduce import reproduce

CHROMIUM = shutil.which("chromium") or (
    str(Path("/usr/bin/chromium")) if Path("/usr/bin/chromium").exists() else None
)

pytestmark = pytest.mark.skipif(
    CHROMIUM is None,
    reason="headless Chromium not found (Debian package 'chromium': apt-get install -y chromium); "
    "this test installs nothing itself",
)

_PROBE = """<script>(function () {
  var errs = [];
  var push = function (m) { errs.push(String(m)); };
  var origError = console.error;
  console.error = function () { push("console.error: " + Array.prototype.join.call(arguments, " "));
                                return origError.apply(console, arguments); };
  window.addEventListener("error", function (ev) {
    var t = ev.target;
    if (t && t !== window && t.tagName) { push("resource error: " + t.tagName); }
    else { push("uncaught: " + ev.message); }
  }, true);
  window.addEventListener("unhandledrejection", function (ev) { push("unhandled rejection: " + ev.reason); });
  window.addEventListener("load", function () {
    var sections = Array.prototype.map.call(document.querySelectorAll("section.paper"), function (s) {
      var r = s.getBoundingClientRect();
      var imgs = Array.prototype.map.call(s.querySelectorAll("img.figure-img"), function (im) {
        return {complete: im.complete, w: im.naturalWidth, h: im.naturalHeight, shown: im.getBoundingClientRect().width};
      });
      return {id: s.id, status: s.getAttribute("data-status"), width: r.width, height: r.height, images: imgs,
              rows: s.querySelectorAll("table.comparison tbody tr").length,
              checks: s.querySelectorAll("table.checks tbody tr").length,
              plots: s.querySelectorAll(".js-plotly-plot").length};
    });
    var probe = document.createElement("pre");
    probe.id = "__probe";
    probe.textContent = JSON.stringify({sections: sections, errors: errs,
                                        overview: document.querySelectorAll("table.overview tbody tr").length,
                                        metadata: !!document.getElementById("run-metadata")});
    document.body.appendChild(probe);
  });
})();</script>"""

# Notices Chromium itself prints about software rendering; they are not page errors.
_BENIGN = re.compile(r"GL Driver Message|willReadFrequently|software WebGL|SwiftShader", re.I)
_ERRORISH = re.compile(
    r"uncaught|error|exception|failed|refused|not allowed|cannot|undefined", re.I
)


def _render(page: Path, workdir: Path) -> tuple[dict, list[str]]:
    text = page.read_text(encoding="utf-8")
    assert '<meta charset="utf-8">' in text
    probe_page = page.with_name("__probe.html")
    probe_page.write_text(
        text.replace('<meta charset="utf-8">', '<meta charset="utf-8">' + _PROBE, 1),
        encoding="utf-8",
    )
    cmd = [
        CHROMIUM,
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader",
        "--no-first-run",
        "--disable-extensions",
        "--mute-audio",
        f"--user-data-dir={workdir / 'chromium-profile'}",
        "--window-size=1280,2000",
        "--enable-logging=stderr",
        "--v=0",
        "--virtual-time-budget=8000",
        "--dump-dom",
        probe_page.resolve().as_uri(),
    ]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=90)
    assert proc.returncode == 0, proc.stderr[-3000:]
    match = re.search(r'<pre id="__probe">(.*?)</pre>', proc.stdout, re.S)
    assert match, "probe did not run (page load event never fired?)\n" + proc.stderr[-3000:]
    probe = json.loads(html.unescape(match.group(1)))
    console = [line for line in proc.stderr.splitlines() if ":CONSOLE" in line]
    return probe, console


def test_index_renders_in_headless_chromium(tmp_path):
    with_3d = plotly_available()
    avail = {
        "alpha": ok_reproduction("alpha", figure_sizes=((40, 30), (24, 18)), trajectory=with_3d),
        "broken": failing_reproduction("broken"),
        "gamma": ok_reproduction("gamma", figure_sizes=((17, 11),)),
    }
    out = tmp_path / "report"
    result = reproduce(
        ["all"], out, progress=False, available=avail, console=Console(file=io.StringIO())
    )
    assert result["exit_code"] == 1  # "broken" failed; its section must still render

    probe, console = _render(out / "index.html", tmp_path)

    assert probe["errors"] == []
    bad_console = [c for c in console if _ERRORISH.search(c) and not _BENIGN.search(c)]
    assert bad_console == []
    assert probe["overview"] == 3 and probe["metadata"] is True

    sections = {s["id"]: s for s in probe["sections"]}
    assert list(sections) == ["paper-alpha", "paper-broken", "paper-gamma"]
    for s in sections.values():
        assert s["width"] > 0 and s["height"] > 0, s  # laid out and visible
    assert [s["status"] for s in sections.values()] == ["ok", "failed", "ok"]
    # every figure decoded, at exactly the pixel size the fake PNG has, and displayed
    sizes = {sid: [(im["w"], im["h"]) for im in s["images"]] for sid, s in sections.items()}
    assert sizes == {
        "paper-alpha": [(40, 30), (24, 18)],
        "paper-broken": [],
        "paper-gamma": [(17, 11)],
    }
    assert all(im["complete"] and im["shown"] > 0 for s in sections.values() for im in s["images"])
    assert [s["rows"] for s in sections.values()] == [3, 0, 3]
    assert [s["checks"] for s in sections.values()] == [3, 0, 3]
    if with_3d:  # Plotly.newPlot ran without error for the one trajectory view
        assert [s["plots"] for s in sections.values()] == [1, 0, 0]
