"""Static HTML page of a reproduction report (``DIR/index.html``).

The page is rendered (template ``report/templates/reproduction.html.j2``,
:mod:`formation_ftc.report.templating`) from the per-paper ``report.json`` entries (see
:func:`formation_ftc.report.reproduce.paper_entry`) and the files in ``DIR/<paper>/``: no network
is needed to view it -- figures are embedded as base64 data URIs, the style sheet is inline and,
when an interactive 3-D view is drawn, the page loads plotly's JavaScript bundle from
``DIR/plotly.min.js``, one copy for the whole report tree (:func:`plotly_script`).

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
import json
import math
import mimetypes
from collections.abc import Callable, Mapping, Sequence
from functools import partial
from pathlib import Path
from typing import Any

__all__ = [
    "TRAJECTORY_FILE",
    "render_index",
    "write_index",
    "write_trajectory3d",
    "load_trajectories",
    "plotly_available",
    "plotly_script",
    "PLOTLY_JS",
]

#: File name a reproduction writes its 3-D trajectory data to (inside its output directory).
TRAJECTORY_FILE = "trajectory3d.json"
#: Points kept per spacecraft in the interactive view (evenly decimated, last point kept).
MAX_POINTS_3D = 2000

_VERDICT_CLASS = {v: "verdict-" + v.replace(" ", "-") for v in ("match", "differs", "not stated")}
#: File name of plotly's JavaScript bundle, one per report tree (:func:`plotly_script`).
PLOTLY_JS = "plotly.min.js"


# ------------------------------------------------------------------------------------------ helpers
def _paragraphs(text: str) -> list[str]:
    return [" ".join(b.split()) for b in str(text or "").split("\n\n") if b.strip()]


def _anchor(paper: str) -> str:
    return "paper-" + "".join(ch if ch.isalnum() or ch in "-_" else "-" for ch in paper)


def _fmt_seconds(value: Any) -> str:
    try:
        return f"{float(value):.1f} s"
    except (TypeError, ValueError):
        return "" if value is None else str(value)


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


def _is_point(p: Any) -> bool:
    """``[x, y, z]`` of finite numbers."""
    return (
        isinstance(p, list | tuple)
        and len(p) == 3
        and all(isinstance(c, int | float) and math.isfinite(c) for c in p)
    )


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
            if isinstance(pts, list) and pts and all(map(_is_point, pts)):
                tracks[str(name)] = _decimate([list(map(float, p)) for p in pts], MAX_POINTS_3D)
            else:
                problems.append(
                    f"{Path(path).name}: track {name!r} is not a list of finite [x, y, z]"
                )
        if tracks:
            labels = view.get("axis_labels") or ["x [m]", "y [m]", "z [m]"]
            labels = [str(a) for a in list(labels)[:3]]
            title = str(view.get("title", "Formation trajectory"))
            views.append({"title": title, "axis_labels": labels, "spacecraft": tracks})
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
        final = dict(x=[xs[-1]], y=[ys[-1]], z=[zs[-1]], name=f"{name} (final)", showlegend=False)
        fig.add_trace(go.Scatter3d(mode="markers", marker=dict(color=color, size=4), **final))
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


# ------------------------------------------------------------------------------------------- public
def league_links(
    out_dir: Path | str, leagues: list[Path | str] | None = None
) -> list[dict[str, Any]]:
    """League leaderboards to link from the report: the given league directories and every
    ``<out_dir>/*/leaderboard/index.html``; each ``{name, seeds, href (relative), ranking, metric,
    tops}`` (``tops``: ``(level, first three methods)`` pairs)."""
    import os

    out_dir = Path(out_dir)
    dirs = [Path(d) for d in (leagues or [])]
    if out_dir.is_dir():
        dirs += sorted(p.parent.parent for p in out_dir.glob("*/leaderboard/index.html"))
    found: dict[str, dict[str, Any]] = {}
    for d in dirs:
        page = d / "leaderboard" / "index.html"
        board_path = d / "leaderboard" / "leaderboard.json"
        key = str(page.resolve())
        if key in found or not (page.is_file() and board_path.is_file()):
            continue
        try:
            board = json.loads(board_path.read_text())
        except (OSError, ValueError):
            continue
        ranking = board.get("ranking", {})
        found[key] = {
            "name": board.get("league", d.name),
            "seeds": board.get("seeds"),
            "href": os.path.relpath(page, out_dir),
            "ranking": ranking,
            "metric": board.get("requirement", {}).get("metric", ""),
            # the first three methods of every level
            "tops": [
                (level, [r.get("method") for r in rows[:3]]) for level, rows in ranking.items()
            ],
        }
    return list(found.values())


def plotly_script(page_dir: Path | str, root: Path | str | None = None) -> str:
    """Relative URL of the plotly bundle for a page in ``page_dir``: the nearest ``plotly.min.js`` at or
    above ``page_dir`` that is this plotly's bundle (one copy serves a whole report tree), else a copy
    written (atomically) into ``root`` (default ``page_dir``, which must be at or below ``root``)."""
    import os

    from plotly.offline import get_plotlyjs

    from formation_ftc.atomic import atomic_write

    page_dir = Path(page_dir).absolute()
    bundle = get_plotlyjs().encode("utf-8")
    for d in (page_dir, *page_dir.parents):
        candidate = d / PLOTLY_JS
        try:
            if candidate.stat().st_size == len(bundle) and candidate.read_bytes() == bundle:
                return Path(os.path.relpath(candidate, page_dir)).as_posix()
        except OSError:  # none there (or unreadable): look further up
            continue
    target = Path(root).absolute() if root is not None else page_dir
    atomic_write(target / PLOTLY_JS, bundle)
    return Path(os.path.relpath(target / PLOTLY_JS, page_dir)).as_posix()


def _rows(entry: dict) -> list[dict[str, Any]]:
    return [
        {
            **{k: r.get(k) for k in ("quantity", "ours", "criterion", "verdict", "note")},
            "class": _VERDICT_CLASS.get(r.get("verdict"), "verdict-not-stated"),  # type: ignore[arg-type]  # a JSON value
            "paper": r.get("published") or "not printed",
            "reference": r.get("reference") or "",
        }
        for r in entry.get("rows") or []
    ]


def _checks(entry: dict) -> list[dict[str, Any]]:
    out = []
    for c in entry.get("checks") or []:
        holds: Any = c.get("holds")  # a JSON value: true, false or null
        basis = c.get("basis") or ""  # absent in a report.json written before the basis existed
        if holds is None and basis in ("sampled", "heuristic"):
            cls, text = "holds-unproven", "unproven"  # no violation found, nothing proved
        else:
            cls, text = {True: ("holds-yes", "yes"), False: ("holds-no", "NO")}.get(
                holds, ("holds-na", "n/a")
            )
        out.append(
            {
                **{k: c.get(k) for k in ("name", "reference", "value", "requirement", "detail")},
                "class": cls,
                "holds": text,
                "basis": basis,
                "required": "yes" if c.get("required", True) else "info",
            }
        )
    return out


def _figures(entry: dict, paper_dir: Path) -> list[dict[str, Any]]:
    out = []
    for f in entry.get("figures") or []:
        path = paper_dir / str(f.get("path", ""))
        src = _data_uri(path) if path.is_file() else None
        out.append({**{k: f.get(k) for k in ("number", "caption", "path")}, "src": src})
    return out


def _trajectory(entry: dict, paper_dir: Path, include_3d: bool) -> dict[str, Any] | None:
    """The 3-D block of a paper: None without trajectory data, else a reason it is not drawn or the
    views (plotly's markup, which loads the page's plotly bundle)."""
    from markupsafe import Markup

    if not entry.get("trajectory3d"):
        return None
    if not include_3d or not plotly_available():
        why = (
            "3-D view left out (--no-3d)."
            if not include_3d
            else "Interactive 3-D view unavailable: plotly is not installed "
            "(pip install plotly, then run the report again)."
        )
        return {"unavailable": why, "problems": [], "views": []}
    views, problems = load_trajectories(paper_dir / str(entry["trajectory3d"]))
    drawn = [
        {
            "title": view["title"],
            "html": Markup(_plotly_view(view, f"{_anchor(str(entry['paper']))}-traj3d-{k + 1}")),
        }
        for k, view in enumerate(views)
    ]
    return {"unavailable": "", "problems": problems, "views": drawn}


def _section(entry: dict, out_dir: Path, include_3d: bool) -> dict[str, Any]:
    paper = str(entry.get("paper"))
    status = entry.get("status", "failed")
    v, c = entry.get("verdicts") or {}, entry.get("checks_summary") or {}
    return {
        "paper": paper,
        "anchor": _anchor(paper),
        "status": status,
        "ok": "ok" if status == "ok" else "failed",
        "title": entry.get("title") or paper,
        "citation": entry.get("citation"),
        "description": _paragraphs(entry.get("description", "")),
        "error": entry.get("error"),
        "warnings": entry.get("warnings") or [],
        "verdicts": {k.replace(" ", "_"): v.get(k, 0) for k in _VERDICT_CLASS},
        "conditions": [c.get(k, 0) for k in ("hold", "fail", "unproven", "not evaluated")],
        "rows": _rows(entry),
        "figures": _figures(entry, out_dir / paper),
        "trajectory": _trajectory(entry, out_dir / paper, include_3d),
        "checks": _checks(entry),
        "errata": entry.get("errata") or [],
        "notes": entry.get("notes") or [],
        "seeds": ", ".join(str(s) for s in entry.get("seeds") or []) or "none",
        "scenarios": ", ".join(str(s) for s in entry.get("scenarios") or []) or "none",
        "wall_time": _fmt_seconds(entry.get("wall_time_s")),
        "finished": entry.get("finished_utc"),
    }


def _render(
    entries: list[dict],
    out_dir: Path,
    metadata: Mapping[str, Any],
    include_3d: bool,
    title: str,
    leagues: list[Path | str] | None,
    plotly_src: Callable[[], str],
) -> str:
    """The page's text; ``plotly_src()`` is called only when the page draws a 3-D view."""
    from formation_ftc.report.templating import render

    sections = [_section(e, out_dir, include_3d) for e in entries]
    uses_plotly = any(s["trajectory"] and s["trajectory"]["views"] for s in sections)
    n_failed = sum(1 for e in entries if e.get("status") != "ok")
    status_line = f"{len(entries)} paper(s), " + (f"{n_failed} failed" if n_failed else "all ran")
    return render(
        "reproduction.html.j2",
        title=title,
        subtitle=f"{status_line}; generated {metadata.get('created_utc', '')}; "
        f"commit {metadata.get('git_commit', 'unknown')}",
        plotly_src=plotly_src() if uses_plotly else "",
        sections=sections,
        leagues=league_links(out_dir, leagues),
        metadata=[
            (k, v)
            for k, v in metadata.items()
            if not k.startswith("version_") and isinstance(v, str | int | float)
        ],
        versions=[
            (k[len("version_") :], v) for k, v in metadata.items() if k.startswith("version_")
        ],
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
    ``out_dir/<paper>/``. The result references no external resource; a page with a 3-D view loads
    ``plotly.min.js`` from ``out_dir`` (:func:`write_index` writes it there).
    """
    return _render(entries, Path(out_dir), metadata, include_3d, title, leagues, lambda: PLOTLY_JS)


def write_index(
    out_dir: Path | str,
    entries: list[dict],
    metadata: Mapping[str, Any],
    *,
    include_3d: bool = True,
    leagues: list[Path | str] | None = None,
) -> Path:
    """Render :func:`render_index` into ``out_dir/index.html`` (atomically) and return its path; with a
    3-D view, plotly's bundle is written once per report tree (:func:`plotly_script`)."""
    from formation_ftc.atomic import atomic_write

    out_dir = Path(out_dir)
    title = "formation-ftc reproduction report"
    plotly_src = partial(plotly_script, out_dir)  # called only for a page with a 3-D view
    page = _render(entries, out_dir, metadata, include_3d, title, leagues, plotly_src)
    return atomic_write(out_dir / "index.html", page)
