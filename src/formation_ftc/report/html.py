"""Self-contained static HTML page of a reproduction report (``DIR/index.html``).

The page is rendered from the per-paper ``report.json`` entries (see
:func:`formation_ftc.report.reproduce.paper_entry`) and the files in ``DIR/<paper>/``: no network
is needed to view it -- figures are embedded as base64 data URIs, the style sheet is inline and,
when the optional interactive 3-D view is on, plotly's own JavaScript bundle is inlined once.

Per paper: title, citation, short method description, the paper-vs-reproduced comparison table
(verdicts coloured), the figures with the paper's numbers and captions, the condition-check table,
the errata applied, notes, warnings, the traceback of a failed run, and the run metadata (scenarios,
seeds, wall time). At the end: provenance (package versions, git commit, Python, platform).

Optional 3-D trajectories: a reproduction writes ``trajectory3d.json`` into its output directory
(use :func:`write_trajectory3d`), holding one view or a list of views::

    {"title": "Li2020 Thm 1 formation (LVLH)", "axis_labels": ["x [m]", "y [m]", "z [m]"],
     "spacecraft": {"SC1": [[x, y, z], ...], "SC2": [[x, y, z], ...]}}

The view is drawn with plotly when it is installed (and ``include_3d`` is True); otherwise the page
says that the interactive view is unavailable and everything else still works.
"""

from __future__ import annotations

import base64
import html
import json
import math
import mimetypes
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

__all__ = [
    "TRAJECTORY_FILE",
    "render_index",
    "write_index",
    "write_trajectory3d",
    "load_trajectories",
    "plotly_available",
]

#: File name a reproduction writes its 3-D trajectory data to (inside its output directory).
TRAJECTORY_FILE = "trajectory3d.json"
#: Points kept per spacecraft in the interactive view (evenly decimated, last point kept).
MAX_POINTS_3D = 2000

_VERDICT_CLASS = {
    "match": "verdict-match",
    "differs": "verdict-differs",
    "not stated": "verdict-not-stated",
}

_CSS = """
:root { --ok:#1e7b34; --okbg:#e3f4e6; --bad:#b3261e; --badbg:#fbe4e2; --na:#5f6368; --nabg:#eef0f2; }
* { box-sizing: border-box; }
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; margin: 0; color: #1f2328;
       background: #fafbfc; line-height: 1.45; }
header.top { background: #0b3d62; color: #fff; padding: 18px 32px; }
header.top h1 { margin: 0 0 4px 0; font-size: 1.5em; }
header.top p { margin: 0; opacity: .85; }
main { max-width: 1200px; margin: 0 auto; padding: 16px 32px 48px; }
section.paper { background: #fff; border: 1px solid #d0d7de; border-radius: 8px; padding: 8px 24px 20px;
                margin: 24px 0; }
section.paper.failed { border-color: var(--bad); }
h2 { margin-top: 16px; } h3 { margin-bottom: 6px; border-bottom: 1px solid #eaeef2; padding-bottom: 2px; }
.citation { color: #57606a; font-style: italic; }
table { border-collapse: collapse; width: 100%; margin: 8px 0; font-size: .92em; }
th, td { border: 1px solid #d0d7de; padding: 4px 8px; text-align: left; vertical-align: top; }
th { background: #f3f5f7; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
tr.verdict-match td.verdict, tr.holds-yes td.holds, .badge.ok { background: var(--okbg); color: var(--ok); }
tr.verdict-differs td.verdict, tr.holds-no td.holds, .badge.failed { background: var(--badbg); color: var(--bad); }
tr.verdict-not-stated td.verdict, tr.holds-na td.holds, tr.holds-unproven td.holds { background: var(--nabg); color: var(--na); }
td.verdict, td.holds { font-weight: 600; white-space: nowrap; }
.badge { display: inline-block; padding: 1px 8px; border-radius: 10px; font-weight: 600; font-size: .85em; }
.figures { display: flex; flex-wrap: wrap; gap: 16px; }
figure.fig { margin: 0; flex: 1 1 460px; max-width: 100%; border: 1px solid #eaeef2; padding: 8px;
             background: #fff; }
figure.fig img { max-width: 100%; height: auto; display: block; margin: 0 auto; }
figcaption { font-size: .9em; color: #333; margin-top: 4px; }
.missing, .unavailable { color: var(--na); background: var(--nabg); padding: 6px 10px; border-radius: 4px; }
.warning { color: #7a4b00; background: #fff4d6; padding: 6px 10px; border-radius: 4px; margin: 4px 0; }
pre.traceback { background: #1f2328; color: #f6f8fa; padding: 10px; overflow-x: auto; font-size: .85em; }
.traj3d { width: 100%; height: 520px; }
dl.meta { display: grid; grid-template-columns: max-content auto; gap: 2px 16px; font-size: .92em; }
dl.meta dt { font-weight: 600; } dl.meta dd { margin: 0; font-family: ui-monospace, monospace; }
nav.toc a { margin-right: 14px; }
footer { color: #57606a; font-size: .85em; }
"""


# ------------------------------------------------------------------------------------------ helpers
def _e(value: Any) -> str:
    return html.escape("" if value is None else str(value), quote=True)


def _paragraphs(text: str) -> str:
    blocks = [b.strip() for b in str(text or "").split("\n\n") if b.strip()]
    return "\n".join(f"<p>{_e(' '.join(b.split()))}</p>" for b in blocks)


def _anchor(paper: str) -> str:
    return "paper-" + "".join(ch if ch.isalnum() or ch in "-_" else "-" for ch in paper)


def _fmt_seconds(value: Any) -> str:
    try:
        return f"{float(value):.1f} s"
    except (TypeError, ValueError):
        return _e(value)


def plotly_available() -> bool:
    """True when plotly can be imported (the optional interactive 3-D view needs it)."""
    try:
        import plotly  # noqa: F401
    except ImportError:
        return False
    return True


def _data_uri(path: Path) -> str:
    mime = mimetypes.guess_type(path.name)[0] or "application/octet-stream"
    return f"data:{mime};base64," + base64.b64encode(path.read_bytes()).decode("ascii")


# ------------------------------------------------------------------------------- 3-D trajectory data
def _decimate(points: list, max_points: int) -> list:
    n = len(points)
    if n <= max_points:
        return points
    idx = sorted({round(k * (n - 1) / (max_points - 1)) for k in range(max_points)})
    return [points[i] for i in idx]


def write_trajectory3d(
    out_dir: Path | str,
    spacecraft: Mapping[str, Any],
    title: str = "Formation trajectory",
    axis_labels: Sequence[str] = ("x [m]", "y [m]", "z [m]"),
    max_points: int = MAX_POINTS_3D,
    append: bool = True,
) -> Path:
    """Write (or append to) ``out_dir/trajectory3d.json`` for the report's interactive 3-D view.

    Parameters
    ----------
    spacecraft : ``{name: positions}`` with positions of shape (n_samples, 3) [m] (numpy or JAX array,
        nested lists); evenly decimated to at most ``max_points`` samples (the last one kept).
    title : view title; ``axis_labels`` : the three axis titles with units.
    append : add a view to an existing file instead of replacing it.
    """
    import numpy as np

    tracks = {}
    for name, pos in spacecraft.items():
        arr = np.asarray(pos, dtype=float)
        if arr.ndim != 2 or arr.shape[1] != 3:
            raise ValueError(f"trajectory of {name!r} must have shape (n, 3), got {arr.shape}")
        tracks[str(name)] = _decimate(arr.tolist(), max_points)
    if len(axis_labels) != 3:
        raise ValueError(f"axis_labels needs 3 entries, got {len(axis_labels)}")
    view = {"title": str(title), "axis_labels": [str(a) for a in axis_labels], "spacecraft": tracks}
    path = Path(out_dir) / TRAJECTORY_FILE
    views = load_trajectories(path)[0] if (append and path.is_file()) else []
    views.append(view)
    path.write_text(json.dumps(views if len(views) > 1 else views[0]), encoding="utf-8")
    return path


def load_trajectories(path: Path) -> tuple[list[dict], list[str]]:
    """Read a ``trajectory3d.json``; returns ``(valid views, problems)`` (bad entries are skipped)."""
    problems: list[str] = []
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        return [], [f"{Path(path).name}: cannot be read ({exc})"]
    raw_views = data if isinstance(data, list) else [data]
    views = []
    for k, view in enumerate(raw_views):
        if (
            not isinstance(view, dict)
            or not isinstance(view.get("spacecraft"), dict)
            or not view["spacecraft"]
        ):
            problems.append(f"{Path(path).name}: view {k + 1} has no 'spacecraft' mapping")
            continue
        tracks = {}
        for name, pts in view["spacecraft"].items():
            ok = (
                isinstance(pts, list)
                and pts
                and all(
                    isinstance(p, list | tuple)
                    and len(p) == 3
                    and all(isinstance(c, int | float) and math.isfinite(c) for c in p)
                    for p in pts
                )
            )
            if ok:
                tracks[str(name)] = _decimate([list(map(float, p)) for p in pts], MAX_POINTS_3D)
            else:
                problems.append(
                    f"{Path(path).name}: track {name!r} is not a list of finite [x, y, z]"
                )
        if tracks:
            labels = view.get("axis_labels") or ["x [m]", "y [m]", "z [m]"]
            views.append(
                {
                    "title": str(view.get("title", "Formation trajectory")),
                    "axis_labels": [str(a) for a in list(labels)[:3]],
                    "spacecraft": tracks,
                }
            )
    return views, problems


def _plotly_view(view: dict, div_id: str) -> str:
    import plotly.graph_objects as go

    from formation_ftc.plotting import SPACECRAFT_COLORS

    fig = go.Figure()
    for k, (name, pts) in enumerate(view["spacecraft"].items()):
        color = SPACECRAFT_COLORS[k % len(SPACECRAFT_COLORS)]
        xs, ys, zs = zip(*pts, strict=True)
        fig.add_trace(
            go.Scatter3d(x=xs, y=ys, z=zs, mode="lines", name=name, line=dict(color=color, width=4))
        )
        fig.add_trace(
            go.Scatter3d(
                x=[xs[-1]],
                y=[ys[-1]],
                z=[zs[-1]],
                mode="markers",
                name=f"{name} (final)",
                marker=dict(color=color, size=4),
                showlegend=False,
            )
        )
    ax = view["axis_labels"]
    fig.update_layout(
        title=view["title"],
        margin=dict(l=0, r=0, t=40, b=0),
        scene=dict(xaxis_title=ax[0], yaxis_title=ax[1], zaxis_title=ax[2], aspectmode="data"),
    )
    return fig.to_html(
        full_html=False,
        include_plotlyjs=False,
        div_id=div_id,
        default_height="520px",
        config={"displaylogo": False, "responsive": True},
    )


# ------------------------------------------------------------------------------------------ sections
def _comparison_table(rows: list[dict]) -> str:
    if not rows:
        return '<p class="missing">No paper-vs-reproduced rows.</p>'
    # "paper" holds only what the paper prints (with where); values the paper does not print are in
    # "reference", with how they were obtained (docs/references.md of the repository)
    out = [
        '<table class="comparison"><thead><tr><th>quantity</th><th>paper (where printed)</th>'
        "<th>reference (how obtained)</th><th>ours</th><th>criterion</th><th>verdict</th><th>note</th>"
        "</tr></thead><tbody>"
    ]
    for r in rows:
        verdict: Any = r.get("verdict")  # a JSON value
        cls = _VERDICT_CLASS.get(verdict, "verdict-not-stated")
        paper = r.get("published") or "not printed"
        out.append(
            f'<tr class="{cls}"><td>{_e(r.get("quantity"))}</td><td>{_e(paper)}</td>'
            f"<td>{_e(r.get('reference') or '')}</td>"
            f"<td>{_e(r.get('ours'))}</td><td>{_e(r.get('criterion'))}</td>"
            f'<td class="verdict">{_e(r.get("verdict"))}</td><td>{_e(r.get("note"))}</td></tr>'
        )
    out.append("</tbody></table>")
    return "\n".join(out)


def _checks_table(checks: list[dict]) -> str:
    if not checks:
        return '<p class="missing">No conditions declared.</p>'
    out = [
        '<table class="checks"><thead><tr><th>condition</th><th>reference</th><th>value</th>'
        "<th>requirement</th><th>holds</th><th>basis</th><th>required</th><th>detail</th></tr></thead><tbody>"
    ]
    for c in checks:
        holds: Any = c.get("holds")  # a JSON value: true, false or null
        basis = c.get("basis") or ""  # absent in a report.json written before the basis existed
        if holds is None and basis in ("sampled", "heuristic"):
            cls, text = "holds-unproven", "unproven"  # no violation found, nothing proved
        else:
            cls, text = {True: ("holds-yes", "yes"), False: ("holds-no", "NO")}.get(
                holds, ("holds-na", "n/a")
            )
        required = "yes" if c.get("required", True) else "info"
        out.append(
            f'<tr class="{cls}"><td>{_e(c.get("name"))}</td><td>{_e(c.get("reference"))}</td>'
            f"<td>{_e(c.get('value'))}</td><td>{_e(c.get('requirement'))}</td>"
            f'<td class="holds">{text}</td><td class="basis">{_e(basis)}</td><td>{required}</td>'
            f"<td>{_e(c.get('detail'))}</td></tr>"
        )
    out.append("</tbody></table>")
    return "\n".join(out)


def _figures(entry: dict, paper_dir: Path) -> str:
    figs = entry.get("figures") or []
    if not figs:
        return '<p class="missing">No figures.</p>'
    out = ['<div class="figures">']
    for f in figs:
        label = f"Fig. {_e(f.get('number'))}."
        path = paper_dir / str(f.get("path", ""))
        if path.is_file():
            body = (
                f'<img class="figure-img" src="{_data_uri(path)}" '
                f'alt="Figure {_e(f.get("number"))}: {_e(f.get("caption"))}">'
            )
        else:
            body = f'<p class="missing">figure file {_e(f.get("path"))} is missing</p>'
        out.append(
            f'<figure class="fig" data-figure="{_e(f.get("number"))}">{body}'
            f"<figcaption><b>{label}</b> {_e(f.get('caption'))}</figcaption></figure>"
        )
    out.append("</div>")
    return "\n".join(out)


def _trajectory_block(entry: dict, paper_dir: Path, include_3d: bool, state: dict) -> str:
    if not entry.get("trajectory3d"):
        return ""
    head = "<h3>Interactive 3-D formation trajectory</h3>"
    if not include_3d:
        return head + '<p class="unavailable">3-D view left out (--no-3d).</p>'
    if not plotly_available():
        return head + (
            '<p class="unavailable">Interactive 3-D view unavailable: plotly is not installed '
            "(pip install plotly, then run the report again).</p>"
        )
    views, problems = load_trajectories(paper_dir / str(entry["trajectory3d"]))
    parts = [head] + [f'<p class="warning">{_e(p)}</p>' for p in problems]
    for k, view in enumerate(views):
        state["plotly"] = True
        div_id = f"{_anchor(entry['paper'])}-traj3d-{k + 1}"
        parts.append(
            f'<div class="traj3d-wrap" data-view="{_e(view["title"])}">'
            f"{_plotly_view(view, div_id)}</div>"
        )
    return "\n".join(parts)


def _section(entry: dict, out_dir: Path, include_3d: bool, state: dict) -> str:
    paper = str(entry.get("paper"))
    paper_dir = out_dir / paper
    status = entry.get("status", "failed")
    badge = f'<span class="badge {"ok" if status == "ok" else "failed"}">{_e(status)}</span>'
    parts = [
        f'<section class="paper {"ok" if status == "ok" else "failed"}" id="{_anchor(paper)}" '
        f'data-paper="{_e(paper)}" data-status="{_e(status)}">',
        f"<h2>{_e(entry.get('title') or paper)} {badge}</h2>",
    ]
    if entry.get("citation"):
        parts.append(f'<p class="citation">{_e(entry["citation"])}</p>')
    parts.append(
        "<h3>Method</h3>"
        + (_paragraphs(entry.get("description", "")) or '<p class="missing">No description.</p>')
    )
    if status != "ok":
        parts.append(
            '<h3>Run failed</h3><p class="warning">This reproduction raised an exception; '
            "the other papers still ran.</p>"
            f'<pre class="traceback">{_e(entry.get("error"))}</pre>'
        )
    for w in entry.get("warnings") or []:
        parts.append(f'<p class="warning">{_e(w)}</p>')
    v = entry.get("verdicts") or {}
    parts.append(
        f"<h3>Published vs reproduced</h3><p>{v.get('match', 0)} match, {v.get('differs', 0)} "
        f"differ, {v.get('not stated', 0)} not stated.</p>"
    )
    parts.append(_comparison_table(entry.get("rows") or []))
    parts.append("<h3>Figures</h3>" + _figures(entry, paper_dir))
    parts.append(_trajectory_block(entry, paper_dir, include_3d, state))
    parts.append("<h3>Condition checks</h3>" + _checks_table(entry.get("checks") or []))
    errata = entry.get("errata") or []
    parts.append(
        "<h3>Errata applied</h3>"
        + (
            '<ul class="errata">'
            + "".join(
                f"<li><code>{_e(e.get('id'))}</code> {_e(e.get('text'))}</li>" for e in errata
            )
            + "</ul>"
            if errata
            else '<p class="missing">None.</p>'
        )
    )
    notes = entry.get("notes") or []
    if notes:
        parts.append(
            '<h3>Notes</h3><ul class="notes">'
            + "".join(f"<li>{_e(n)}</li>" for n in notes)
            + "</ul>"
        )
    seeds = ", ".join(str(s) for s in entry.get("seeds") or []) or "none"
    scenarios = ", ".join(str(s) for s in entry.get("scenarios") or []) or "none"
    parts.append(
        '<h3>Run metadata</h3><dl class="meta">'
        f"<dt>wall time</dt><dd>{_fmt_seconds(entry.get('wall_time_s'))}</dd>"
        f"<dt>seeds</dt><dd>{_e(seeds)}</dd><dt>scenarios</dt><dd>{_e(scenarios)}</dd>"
        f"<dt>finished</dt><dd>{_e(entry.get('finished_utc'))}</dd>"
        f"<dt>output</dt><dd>{_e(paper)}/ (report.json, summary.json, figures)</dd></dl>"
    )
    parts.append("</section>")
    return "\n".join(p for p in parts if p)


def _overview(entries: list[dict]) -> str:
    out = [
        '<table class="overview"><thead><tr><th>paper</th><th>status</th><th>match</th><th>differs</th>'
        "<th>not stated</th><th>conditions hold / fail / unproven / n.a.</th><th>figures</th><th>wall time</th>"
        "</tr></thead><tbody>"
    ]
    for e in entries:
        v, c = e.get("verdicts") or {}, e.get("checks_summary") or {}
        status = e.get("status", "failed")
        out.append(
            f'<tr><td><a href="#{_anchor(str(e.get("paper")))}">{_e(e.get("paper"))}</a></td>'
            f'<td><span class="badge {"ok" if status == "ok" else "failed"}">{_e(status)}</span></td>'
            f'<td class="num">{v.get("match", 0)}</td><td class="num">{v.get("differs", 0)}</td>'
            f'<td class="num">{v.get("not stated", 0)}</td>'
            f'<td class="num">{c.get("hold", 0)} / {c.get("fail", 0)} / {c.get("unproven", 0)} / '
            f"{c.get('not evaluated', 0)}</td>"
            f'<td class="num">{len(e.get("figures") or [])}</td>'
            f'<td class="num">{_fmt_seconds(e.get("wall_time_s"))}</td></tr>'
        )
    out.append("</tbody></table>")
    return "\n".join(out)


def _metadata_block(metadata: Mapping[str, Any]) -> str:
    versions = {k[len("version_") :]: v for k, v in metadata.items() if k.startswith("version_")}
    other = {
        k: v
        for k, v in metadata.items()
        if not k.startswith("version_") and isinstance(v, str | int | float)
    }
    rows = "".join(f"<dt>{_e(k)}</dt><dd>{_e(v)}</dd>" for k, v in other.items())
    vrows = "".join(f"<tr><td>{_e(k)}</td><td>{_e(v)}</td></tr>" for k, v in versions.items())
    return (
        '<section class="run-metadata" id="run-metadata"><h2>Run metadata</h2>'
        f'<dl class="meta">{rows}</dl><h3>Package versions</h3>'
        f'<table class="versions"><thead><tr><th>package</th><th>version</th></tr></thead>'
        f"<tbody>{vrows}</tbody></table></section>"
    )


# ------------------------------------------------------------------------------------------- public
def league_links(
    out_dir: Path | str, leagues: list[Path | str] | None = None
) -> list[dict[str, Any]]:
    """League leaderboards to link from the report: the given league directories and every
    ``<out_dir>/*/leaderboard/index.html``; each ``{name, href (relative), ranking}``."""
    import os

    out_dir = Path(out_dir)
    dirs = [Path(d) for d in (leagues or [])]
    if out_dir.is_dir():
        dirs += sorted(p.parent.parent for p in out_dir.glob("*/leaderboard/index.html"))
    found: dict[str, dict[str, Any]] = {}
    for d in dirs:
        page = d / "leaderboard" / "index.html"
        board_path = d / "leaderboard" / "leaderboard.json"
        if not page.is_file() or not board_path.is_file():
            continue
        key = str(page.resolve())
        if key in found:
            continue
        try:
            board = json.loads(board_path.read_text())
        except (OSError, ValueError):
            continue
        found[key] = {
            "name": board.get("league", d.name),
            "seeds": board.get("seeds"),
            "href": os.path.relpath(page, out_dir),
            "ranking": board.get("ranking", {}),
            "metric": board.get("requirement", {}).get("metric", ""),
        }
    return list(found.values())


def _league_block(links: list[dict[str, Any]]) -> str:
    if not links:
        return ""
    items = []
    for lk in links:
        tops = "; ".join(
            f"{_e(level)}: " + ", ".join(_e(r.get("method")) for r in rows[:3])
            for level, rows in lk["ranking"].items()
        )
        items.append(
            f'<li><a href="{_e(lk["href"])}">league {_e(lk["name"])}</a> ({_e(lk["seeds"])} seeds per '
            f"cell; top three by pass rate on {_e(lk['metric'])}: {tops})</li>"
        )
    return (
        '<section id="leagues"><h2>FTC league leaderboards</h2><p>Every method on one realistic truth under '
        "the same fault battery (<code>formation-ftc league</code>):</p><ul>"
        + "".join(items)
        + "</ul></section>"
    )


def render_index(
    entries: list[dict],
    out_dir: Path | str,
    metadata: Mapping[str, Any],
    *,
    include_3d: bool = True,
    title: str = "formation-ftc reproduction report",
    leagues: list[Path | str] | None = None,
) -> str:
    """The complete HTML text of the report page.

    ``entries`` are the per-paper ``report.json`` dicts; figure and trajectory files are read from
    ``out_dir/<paper>/``. The result references no external resource.
    """
    out_dir = Path(out_dir)
    state: dict[str, bool] = {"plotly": False}
    sections = [_section(e, out_dir, include_3d, state) for e in entries]
    n_failed = sum(1 for e in entries if e.get("status") != "ok")
    head_js = ""
    if state["plotly"]:
        from plotly.offline import get_plotlyjs

        head_js = f'<script type="text/javascript">{get_plotlyjs()}</script>'
    toc = " ".join(
        f'<a href="#{_anchor(str(e.get("paper")))}">{_e(e.get("paper"))}</a>' for e in entries
    )
    status_line = (
        f"{len(entries)} paper(s), all ran"
        if not n_failed
        else f"{len(entries)} paper(s), {n_failed} failed"
    )
    return "\n".join(
        [
            "<!DOCTYPE html>",
            '<html lang="en"><head><meta charset="utf-8">',
            '<meta name="viewport" content="width=device-width, initial-scale=1">',
            f"<title>{_e(title)}</title><style>{_CSS}</style>{head_js}</head><body>",
            f'<header class="top"><h1>{_e(title)}</h1><p>{_e(status_line)}; generated '
            f"{_e(metadata.get('created_utc', ''))}; commit {_e(metadata.get('git_commit', 'unknown'))}</p></header>",
            "<main>",
            f'<nav class="toc">{toc} <a href="#run-metadata">run metadata</a></nav>',
            '<section class="overview" id="overview"><h2>Overview</h2>'
            + _overview(entries)
            + "</section>",
            _league_block(league_links(out_dir, leagues)),
            *sections,
            _metadata_block(metadata),
            "<footer><p>Written by <code>formation-ftc reproduce</code>. Per-paper data: "
            "<code>&lt;paper&gt;/report.json</code>, <code>&lt;paper&gt;/summary.json</code>; merged: "
            "<code>summary.json</code>.</p></footer>",
            "</main></body></html>",
        ]
    )


def write_index(
    out_dir: Path | str,
    entries: list[dict],
    metadata: Mapping[str, Any],
    *,
    include_3d: bool = True,
    leagues: list[Path | str] | None = None,
) -> Path:
    """Render :func:`render_index` into ``out_dir/index.html`` and return its path."""
    out_dir = Path(out_dir)
    path = out_dir / "index.html"
    tmp = path.with_name("index.html.tmp")
    tmp.write_text(
        render_index(entries, out_dir, metadata, include_3d=include_3d, leagues=leagues),
        encoding="utf-8",
    )
    tmp.replace(path)
    return path
