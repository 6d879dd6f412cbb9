"""League leaderboard: per-fault tables, ranking, Pareto plot, representative trajectories.

``write_leaderboard(DIR)`` reads the finished runs of a league directory and writes

* ``DIR/leaderboard/leaderboard.json`` -- definition, provenance, per-cell statistics, ranking, winners;
* ``DIR/leaderboard/cells.parquet`` -- one row per (method, level, case) cell;
* ``DIR/leaderboard/runs.parquet`` -- one row per run (every score, seed, status, diagnostic);
* ``DIR/leaderboard/ranking.parquet`` -- one row per (level, method) of the ranking, with its
  confidence (:func:`rank_confidence`);
  the Parquet files carry the units of every numeric column (:mod:`formation_ftc.parquet_units`);
* ``DIR/leaderboard/index.html`` -- the self-contained leaderboard page (figures embedded).

Statistics: medians and 95th percentiles over the runs that finished (a diverged run has no score), the
pass rate over every run (a diverged run fails). Ranking, per actuator level: pass rate over the
actuator-fault cases that apply to every method, then the median of the requirement metric; every
ranking row has 95 % intervals and the comparison with the row above on the paired seeds, and methods
that are not separated share a rank (:mod:`formation_ftc.league.statistics`).
"""

from __future__ import annotations

import contextlib
import json
import math
import re
import tomllib
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from formation_ftc.atomic import atomic_write
from formation_ftc.exitcodes import jsonable
from formation_ftc.league import statistics as st
from formation_ftc.league.definition import requirement_of
from formation_ftc.league.runner import load_league_results
from formation_ftc.parquet_units import write_parquet
from formation_ftc.report.html import _data_uri
from formation_ftc.report.templating import fmt, render

__all__ = [
    "cell_table",
    "fdi_table",
    "FDI_COLUMNS",
    "IDENTIFICATION_COLUMNS",
    "IDENTIFICATION_TABLE",
    "IDENTIFICATION_NOTE",
    "ranking",
    "resolution_text",
    "rank_confidence",
    "ranking_frame",
    "seed_column",
    "winners",
    "write_leaderboard",
    "markdown_summary",
    "SCORES",
    "COSTS",
    "tuned_column",
    "completeness",
    "seeds_text",
    "incomplete_note",
]

#: the actuator-usage score a league is ranked and plotted against, with its label (first one present)
COSTS = (("delta_v_total", "total delta-v [m/s]"), ("control_impulse", "control impulse [N m s]"))


def _cost(cells: pd.DataFrame) -> tuple[str, str] | None:
    return next(((name, label) for name, label in COSTS if f"{name}_median" in cells), None)


#: scores shown in the tables (when the league computes them)
SCORES = (
    "rms_shape_error",
    "max_shape_error",
    "rms_slot_error",
    "settle_time",
    "delta_v_total",
    "peak_thrust",
    "saturated_fraction",
    "rms_attitude_error",
    "max_attitude_error",
    "control_impulse",
    "stl_violation",  # an STL requirement's -robustness (league.definition.STL_VIOLATION)
    "mean_nees",  # the navigation filter's consistency (league.runner.NAVIGATION_METRICS)
    "nees_in_band",
    "nis_in_band",
)


def _league(meta: dict[str, Any]) -> dict[str, Any]:
    """The ``[league]`` table of the definition that ``league.json`` records."""
    return tomllib.loads(meta["definition"])["league"]


def _requirement(meta: dict[str, Any]) -> tuple[str, float, str]:
    return requirement_of(_league(meta))


def _col(g: pd.DataFrame, name: str) -> np.ndarray:
    col = f"metric:{name}"
    return g[col].to_numpy(dtype=float) if col in g else np.full(len(g), np.nan)


def _passed(df: pd.DataFrame, metric: str, limit: float) -> np.ndarray:
    return (df["status"] == "ok").to_numpy() & (_col(df, metric) <= limit)


def cell_table(meta: dict[str, Any], runs: pd.DataFrame) -> pd.DataFrame:
    """One row per (method, level, case): runs, failures, pass rate, median and p95 of every score."""
    metric, limit, _ = _requirement(meta)
    runs = runs.assign(passed=_passed(runs, metric, limit))
    rows = []
    for (method, level, case), g in runs.groupby(["method", "level", "case"], sort=False):
        ok = g[g["status"] == "ok"]
        row: dict[str, Any] = {
            "method": method,
            "level": level,
            "case": case,
            "fault_kind": g["fault_kind"].iloc[0],
            "runs": len(g),
            "failed": int((g["status"] != "ok").sum()),
            "pass_rate": float(g["passed"].mean()),
        }
        for s in SCORES:
            if f"metric:{s}" in g:
                v = _col(ok, s)
                v = v[np.isfinite(v)]
                row[f"{s}_median"] = _median(v)
                row[f"{s}_p95"] = float(np.percentile(v, 95)) if v.size else math.nan
        rows.append(row)
    return pd.DataFrame(rows)


#: the FDI table's columns (key, label) -- :func:`fdi_table`
FDI_COLUMNS = (
    ("method", "method"),
    ("level", "level"),
    ("case", "fault case"),
    ("runs", "runs"),
    ("detection_rate", "detection rate"),
    ("mean_detection_delay", "mean detection delay [s]"),
    ("missed", "missed"),
    ("false_alarms", "false alarms"),
    ("false_alarms_per_hour", "false alarms per hour"),
    ("correct_isolation_rate", "correct isolation rate"),
)
#: the columns a method whose FDI identifies adds (identification-scores: league.runner.IDENTIFICATION_METRICS)
IDENTIFICATION_COLUMNS = (
    ("median_identification_error", "median effectiveness error (identified runs)"),
    ("identified_runs", "identified runs"),
    ("median_time_outside_10pct", "median time outside 10 % [s]"),
    ("false_identifications", "false identifications"),
)


#: the identification table's columns
IDENTIFICATION_TABLE = (*FDI_COLUMNS[:4], *IDENTIFICATION_COLUMNS)
#: what the identification table says
IDENTIFICATION_NOTE = (
    "Over the runs with a fault: the median of |identified - true| effectiveness of the faulty "
    "channel at the horizon over the runs where it was identified (their number in 'identified runs'), "
    "the median time after the fault's first departure from nominal during which the identified "
    "effectiveness was not within 10 % (or 0.01) of the true one (not identified counts as not "
    "within), and the runs in which a healthy channel was identified outside 1 +- 0.1."
)


def fdi_table(meta: dict[str, Any], runs: pd.DataFrame) -> dict[str, Any]:
    """The fault detection scores of the methods that fly a fault detector (their runs have the
    league's FDI metrics, :data:`formation_ftc.league.runner.FDI_METRICS`), one row per (method,
    level, case) over the runs that finished:

    * ``detection_rate``: runs with a first alarm at or after the fault's first active sample, over
      the runs with a fault (None for the no-fault case);
    * ``mean_detection_delay`` [s]: mean over those runs of ``fdi_detection_delay``, the time the fault
      was active before the alarm;
    * ``missed``: runs with a fault and no alarm up to the horizon;
    * ``false_alarms``: runs whose first alarm came while no fault was active (the alarm latches: at
      most one per run); ``false_alarms_per_hour``: their number per hour of observed fault-free
      flight (each run up to its first alarm, its fault or the horizon);
    * ``correct_isolation_rate``: detected runs whose isolated (spacecraft, axis) is the faulty one,
      over the detected runs.

    Returns ``{"methods": [...], "without_fdi": [...], "rows": [...]}``; counts are ints, rates and
    times floats (NaN where undefined).
    """
    horizon = float(_league(meta)["horizon"])
    methods = list(dict.fromkeys(runs["method"])) if len(runs) else []
    scored = np.isfinite(_col(runs, "fdi_detection_delay"))
    with_fdi = [m for m in methods if scored[(runs["method"] == m).to_numpy()].any()]
    rows = []
    fdi_runs = runs[runs["method"].isin(with_fdi)]
    for (method, level, case), g in fdi_runs.groupby(["method", "level", "case"], sort=False):
        ok = g[g["status"] == "ok"]
        alarm, fault = _col(ok, "fdi_alarm_time"), _col(ok, "fdi_fault_time")
        faulted, alarmed = np.isfinite(fault), np.isfinite(alarm)
        early = alarmed & (~faulted | (alarm < fault))
        detected = faulted & alarmed & (alarm >= fault)
        exposure = np.minimum(np.where(alarmed, alarm, np.inf), np.where(faulted, fault, horizon))
        hours = float(np.sum(exposure)) / 3600.0
        n_fault = int(faulted.sum())
        delay = _col(ok, "fdi_detection_delay")[detected]
        isolation = _col(ok, "fdi_correct_isolation")[detected]
        ident = {}
        if np.isfinite(_col(ok, "id_time_outside_10pct")).any():  # its FDI identifies
            err = _col(ok, "id_effectiveness_error")[faulted]
            err = err[np.isfinite(err)]
            outside = _col(ok, "id_time_outside_10pct")[faulted]
            ident = {
                "median_identification_error": _median(err),
                "identified_runs": int(err.size),
                "median_time_outside_10pct": _median(outside),
                "false_identifications": int(np.nansum(_col(ok, "id_false_identification"))),
            }
        rows.append(
            {
                "method": str(method),
                "level": str(level),
                "case": str(case),
                "fault_kind": str(g["fault_kind"].iloc[0]),
                "runs": int(len(ok)),
                "failed": int(len(g) - len(ok)),
                "fault_runs": n_fault,
                "detected": int(detected.sum()),
                "detection_rate": float(detected.sum() / n_fault) if n_fault else math.nan,
                "mean_detection_delay": float(np.mean(delay)) if delay.size else math.nan,
                "missed": int((faulted & ~alarmed).sum()),
                "false_alarms": int(early.sum()),
                "false_alarms_per_hour": float(early.sum() / hours) if hours > 0 else math.nan,
                "fault_free_hours": hours,
                "correct_isolation_rate": float(np.mean(isolation)) if isolation.size else math.nan,
                **ident,
            }
        )
    return {
        "methods": with_fdi,
        "without_fdi": [m for m in methods if m not in with_fdi],
        "rows": rows,
    }


def _fdi_note(fdi: dict[str, Any]) -> str:
    """One sentence on who has an FDI in the loop."""
    none = ", ".join(fdi["without_fdi"]) or "none"
    if not fdi["methods"]:
        return "No method flies a fault detector: no FDI in the loop of any method."
    return (
        f"Fault detection of the methods that fly one ({', '.join(fdi['methods'])}), scored against "
        "the true fault of the battery; detection delay: time the fault was active before the first "
        "alarm; false alarms: alarms with no active fault (latched: at most one per run), per hour of "
        f"fault-free flight. No FDI in the loop: {none}."
    )


def _fdi_tables(fdi: dict[str, Any]) -> dict[str, Any]:
    """The FDI section of the page and of the Markdown board, from :func:`fdi_table`: its note, the
    FDI table and the identification table (rows and (key, label) columns of each)."""
    return {
        "note": _fdi_note(fdi),
        "rows": fdi["rows"],
        "columns": list(FDI_COLUMNS),
        # methods whose FDI identifies faults (a table of its own: the FDI table stays within 1,280 px)
        "identification": [r for r in fdi["rows"] if "identified_runs" in r],
        "identification_columns": list(IDENTIFICATION_TABLE),
    }


def _common_cases(cells: pd.DataFrame) -> list[str]:
    """Cases every method was run on (the communication cases apply to networked methods only)."""
    per_method = cells.groupby("method")["case"].apply(set)
    common = set.intersection(*per_method.tolist()) if len(per_method) else set()
    return [c for c in dict.fromkeys(cells["case"]) if c in common]


def ranking(
    meta: dict[str, Any], cells: pd.DataFrame, runs: pd.DataFrame | None = None
) -> dict[str, list[dict[str, Any]]]:
    """Per level: methods by pass rate over the common cases, then by the median requirement metric.

    Without ``runs`` the rank is the position. With the league's ``runs`` (one row per run,
    :func:`~formation_ftc.league.runner.load_league_results`), every row also gets its confidence
    (:func:`rank_confidence`): intervals, the comparison with the row above and shared ranks for
    methods that are not separated; the order is the same."""
    metric, _, _ = _requirement(meta)
    common = _common_cases(cells)
    cost = _cost(cells)
    out: dict[str, list[dict[str, Any]]] = {}
    for level, g in cells.groupby("level", sort=False):
        g = g[g["case"].isin(common)]
        rows = []
        for method, h in g.groupby("method", sort=False):
            w = h["runs"].to_numpy(dtype=float)
            row = {
                "method": method,
                "pass_rate": float(np.average(h["pass_rate"], weights=w)),
                f"{metric}_median": _nanmedian(h[f"{metric}_median"]),
                "failed": int(h["failed"].sum()),
                "runs": int(h["runs"].sum()),
            }
            if cost is not None:
                row[f"{cost[0]}_median"] = _nanmedian(h[f"{cost[0]}_median"])
            rows.append(row)
        rows.sort(key=lambda r: (-r["pass_rate"], _nan_last(r[f"{metric}_median"])))
        for k, r in enumerate(rows, start=1):
            r.update(rank=k, tied=False, rank_display=str(k))
        out[str(level)] = rows
    if runs is not None:
        rank_confidence(meta, runs, out, common)
    return out


def seed_column(runs: pd.DataFrame) -> str:
    """The column of the runs that identifies the paired seed: ``replicate`` (replicate j has the same
    initial errors, fault onset and noise in every cell and for every method), else ``seed``.

    Parameters
    ----------
    runs : pandas.DataFrame
        One row per run.

    Returns
    -------
    str
        The column name.

    Examples
    --------
    >>> seed_column(pd.DataFrame({"seed": [7], "replicate": [0]}))
    'replicate'
    """
    for name in ("replicate", "seed"):
        if name in runs:
            return name
    raise KeyError("the runs have neither a replicate nor a seed column")


#: the keys of the comparison with the row above that :func:`rank_confidence` adds to every ranking
#: row (None on a level's first row)
_COMPARISON_KEYS = (
    "test",
    "statistic",
    "p_value",
    "p_adjusted",
    "separated",
    "pairs",
    "only_above_passed",
    "only_this_passed",
)


def rank_confidence(
    meta: dict[str, Any],
    runs: pd.DataFrame,
    rank: dict[str, list[dict[str, Any]]],
    cases: list[str] | None = None,
) -> None:
    """Give every row of ``rank`` (from :func:`ranking`, changed in place) its confidence, from the runs
    of its method and level on ``cases`` (default: the cases every method ran), paired by (case, seed)
    (:func:`seed_column`); :mod:`formation_ftc.league.statistics` computes every number:

    * ``pass_rate_low``, ``pass_rate_high`` (the 95 % interval; ``pass_rate_interval``: "cluster
      bootstrap" over seeds, or "wilson" when every seed has the same pass fraction; ``seeds``);
    * ``<metric>_median_low``, ``<metric>_median_high`` (bootstrap over seeds of the median over
      cases of the per-case medians of the requirement metric);
    * for every row but the first, the comparison with the row above on their paired runs: ``test``
      ("mcnemar" or "wilcoxon"), ``statistic``, ``p_value``, ``p_adjusted`` (Holm over the level's
      adjacent comparisons), ``separated`` (adjusted p < 0.05), ``pairs``, ``only_above_passed`` and
      ``only_this_passed`` (the discordant pairs);
    * ``rank`` (shared by a tie group: consecutive methods not separated), ``tied``, ``rank_display``
      ("3=" for a tie).
    """
    metric, limit, _ = _requirement(meta)
    seed = seed_column(runs)
    if cases is None:
        cases = _common_cases(runs[["method", "case"]].drop_duplicates())
    sel = runs[runs["case"].isin(cases)]
    frame = (
        sel[["method", "level", "case"]]
        .astype(str)
        .assign(
            seed=sel[seed],
            passed=_passed(sel, metric, limit),
            value=np.where(sel["status"] == "ok", _col(sel, metric), np.nan),
        )
    )
    groups = {key: g for key, g in frame.groupby(["method", "level"], sort=False)}
    empty = frame.iloc[:0]
    for level, rows in rank.items():
        if not rows:
            continue
        per = [groups.get((str(r["method"]), str(level)), empty) for r in rows]
        for r, g in zip(rows, per, strict=True):
            ci = st.pass_rate_interval(g["passed"].to_numpy(), g["seed"].to_numpy())
            r["pass_rate_low"], r["pass_rate_high"] = ci["low"], ci["high"]
            r["pass_rate_interval"], r["seeds"] = ci["method"], ci["seeds"]
            lo = hi = math.nan
            if len(g):
                matrix = g.pivot_table(
                    index="seed", columns="case", values="value", aggfunc="median", dropna=False
                )
                lo, hi = st.median_interval(matrix.to_numpy(dtype=float))
            r[f"{metric}_median_low"], r[f"{metric}_median_high"] = lo, hi
        tests = []
        for above, this in zip(per, per[1:], strict=False):
            pair = above.merge(this, on=["case", "seed"], suffixes=("_a", "_b"))
            paired = (pair[c].to_numpy() for c in ("passed_a", "passed_b", "value_a", "value_b"))
            tests.append(st.paired_comparison(*paired))
        adjusted = st.holm([t["p_value"] for t in tests])
        separated = [bool(p < st.ALPHA) for p in adjusted]
        rows[0].update(dict.fromkeys(_COMPARISON_KEYS))
        for r, t, p, sep in zip(rows[1:], tests, adjusted, separated, strict=True):
            t = t | {"p_adjusted": float(p), "separated": sep}
            t |= {"only_above_passed": t["a_only"], "only_this_passed": t["b_only"]}
            r.update({k: t[k] for k in _COMPARISON_KEYS})
        for r, tie in zip(rows, st.tie_groups(separated), strict=True):
            r.update(tie)


def _median(v: np.ndarray) -> float:
    """The median of ``v`` (NaN when it is empty)."""
    return float(np.median(v)) if v.size else math.nan


def _nanmedian(v) -> float:
    a = np.asarray(v, dtype=float)
    return _median(a[np.isfinite(a)])


def _nan_last(v: float | None) -> float:
    """Sort key: a missing (None) or non-finite median after every finite one."""
    return math.inf if v is None or not math.isfinite(v) else float(v)


def winners(meta: dict[str, Any], cells: pd.DataFrame) -> list[dict[str, Any]]:
    """Per (level, case): the method with the highest pass rate, ties broken by the median metric."""
    return _winners(cells, _requirement(meta)[0])


def _winners(cells: pd.DataFrame, metric: str) -> list[dict[str, Any]]:
    shown = ("method", "pass_rate", f"{metric}_median")
    out = []
    for (level, case), g in cells.groupby(["level", "case"], sort=False):
        best = min(
            g.to_dict("records"), key=lambda r: (-r["pass_rate"], _nan_last(r[f"{metric}_median"]))
        )
        out.append({"level": level, "case": case, **{k: best[k] for k in shown}})
    return out


def _expected_cells(league_dir: Path, method: str) -> list[str] | None:
    """The cells (``case--level``) a method's campaign plans, or its cell files; None when neither is
    there (the method's directory is missing)."""
    from formation_ftc.campaign.storage import MANIFEST

    with contextlib.suppress(OSError, ValueError, KeyError, TypeError):  # then the cell files
        manifest = json.loads((league_dir / method / "campaign" / MANIFEST).read_text("utf-8"))
        bases = manifest["plan"]["bases"]
        if isinstance(bases, list) and all(isinstance(b, str) for b in bases):
            return [Path(b).stem for b in bases]
    cdir = league_dir / method / "cells"
    return sorted(p.stem for p in cdir.glob("*.toml")) if cdir.is_dir() else None


def completeness(
    meta: dict[str, Any], runs: pd.DataFrame, league_dir: str | Path
) -> dict[str, Any]:
    """What of the league in ``league_dir`` has finished: every method of ``league.json`` against the
    cells its campaign plans, each with ``meta["seeds"]`` runs.

    Returns ``{"complete", "seeds" (configured per cell), "seeds_per_cell" ({"min", "max"} of the
    runs found per planned cell; 0 for a cell without any), "runs", "expected_runs" (over the
    methods whose cells are known), "missing_methods" (no run at all; ``cells_unknown``: of those,
    the ones whose directory is missing), "incomplete_cells" (``method``, ``case``, ``level``,
    ``runs``, ``expected``)}``.
    """
    seeds = int(meta["seeds"])
    cell = ["method", "case", "level"]
    counts = runs.groupby(cell, sort=False).size().to_dict() if len(runs) else {}
    names = [r["name"] for r in meta["methods"]]
    found = {m for m, _, _ in counts}
    missing = [m for m in names if m not in found]
    per_cell: list[int] = []
    short: list[dict[str, Any]] = []
    unknown = []
    for m in names:
        keys = _expected_cells(Path(league_dir), m)
        if keys is None:
            unknown.append(m)
            continue
        for key in keys:
            case, _, level = key.partition("--")
            n = int(counts.get((m, case, level), 0))
            per_cell.append(n)
            if n < seeds:
                short.append(dict(method=m, case=case, level=level, runs=n, expected=seeds))
    return {
        "complete": not missing and not short,
        "seeds": seeds,
        "seeds_per_cell": {"min": min(per_cell, default=0), "max": max(per_cell, default=0)},
        "runs": int(len(runs)),
        "expected_runs": seeds * len(per_cell),
        "missing_methods": missing,
        "cells_unknown": unknown,
        "incomplete_cells": short,
    }


def seeds_text(comp: dict[str, Any]) -> str:
    """The seeds per cell as the leaderboard's header states them: the configured count when the league
    is complete, else the counts found.

    Examples
    --------
    >>> seeds_text({"complete": False, "seeds": 3, "seeds_per_cell": {"min": 2, "max": 3}})
    '2-3 seeds per cell (3 configured)'
    """
    lo, hi = comp["seeds_per_cell"]["min"], comp["seeds_per_cell"]["max"]
    if comp["complete"]:
        lo = hi = comp["seeds"]
    text = f"{lo} seed{'' if lo == 1 else 's'}" if lo == hi else f"{lo}-{hi} seeds"
    return f"{text} per cell" + ("" if comp["complete"] else f" ({comp['seeds']} configured)")


def incomplete_note(comp: dict[str, Any], limit: int = 8) -> str | None:
    """One paragraph on what is missing (None for a complete league)."""
    if comp["complete"]:
        return None
    found = f"{comp['runs']:,} of {comp['expected_runs']:,} planned runs found"
    unknown = " (more for the methods without a directory)" if comp["cells_unknown"] else ""
    parts = [f"INCOMPLETE league: {found}{unknown}"]
    if comp["missing_methods"]:
        parts.append(f"methods without results: {', '.join(comp['missing_methods'])}")
    short = [c for c in comp["incomplete_cells"] if c["method"] not in comp["missing_methods"]]
    if short:
        shown = ", ".join(
            f"{c['method']} {c['case']}/{c['level']} ({c['runs']} of {c['expected']} runs)"
            for c in short[:limit]
        )
        more = f" and {len(short) - limit} more" if len(short) > limit else ""
        parts.append(f"cells short of their seeds: {shown}{more}")
    return "; ".join(parts) + (
        ". The tables rank what finished; run `formation-ftc league run` on the directory again "
        "to complete it."
    )


# ---------------------------------------------------------------------------------------------- figures
def _pareto(meta, cells: pd.DataFrame, out: Path) -> list[Path]:
    from formation_ftc.plotting import new_figure, save_figure

    metric, limit, units = _requirement(meta)
    cost = _cost(cells)
    if cost is None:
        return []
    paths = []
    for level, g in cells[cells["case"].isin(_common_cases(cells))].groupby("level", sort=False):
        agg = g.groupby("method", sort=False)[[f"{metric}_median", f"{cost[0]}_median"]].median()
        title = f"{meta['name']} league, {level}: {cost[0]} vs accuracy (median over cases)"
        fig, axes = new_figure(1, 1, width=6.4, height=4.2, title=title)
        ax = axes[0, 0]
        pts = agg.to_numpy(dtype=float)
        for name, (acc, dv) in zip(agg.index, pts, strict=True):
            if math.isfinite(acc) and math.isfinite(dv):
                ax.scatter(dv, acc, s=30)
                ax.annotate(name, (dv, acc), fontsize=7, xytext=(3, 3), textcoords="offset points")
        front = _pareto_front(pts)
        if front:
            f = sorted((pts[i][1], pts[i][0]) for i in front)
            ax.plot([p[0] for p in f], [p[1] for p in f], "k--", lw=0.8, label="Pareto front")
        ax.axhline(limit, color="tab:red", lw=0.8, label=f"requirement {limit:g} {units}")
        ax.set_xlabel(f"{cost[1]}, median")
        ax.set_ylabel(f"{metric}, median [{units}]")
        for k, set_scale in ((0, ax.set_yscale), (1, ax.set_xscale)):  # accuracy, actuator usage
            v = pts[:, k][np.isfinite(pts[:, k])]
            if v.size and v.min() > 0 and v.max() / v.min() > 100:
                set_scale("log")
        ax.legend(loc="best", fontsize=7)
        paths.append(save_figure(fig, out / f"pareto-{level}.png"))
    return paths


def _pareto_front(pts: np.ndarray) -> list[int]:
    """Indices of the points no other point beats on both accuracy (col 0) and delta-v (col 1)."""
    finite = np.flatnonzero(np.isfinite(pts).all(axis=1))
    p = pts[finite, None, :], pts[None, finite, :]  # (beater, beaten)
    dominated = ((p[0] <= p[1]).all(axis=2) & (p[0] < p[1]).any(axis=2)).any(axis=0)
    return [int(i) for i in finite[~dominated]]


def _trajectories(meta, league_dir: Path, out: Path) -> list[Path]:
    """Each method's score signal against time for the traced seed, one panel per fault case."""
    import xarray as xr

    from formation_ftc.plotting import new_figure, save_figure

    metric, limit, units = _requirement(meta)
    signal = "shape_error" if meta.get("kind", "translational") != "attitude" else "attitude_error"
    traces: dict[str, dict[str, Any]] = {}
    for m in meta["methods"]:
        tdir = league_dir / m["name"] / "campaign" / "traces"
        if not tdir.is_dir():
            continue
        runs = int(meta["seeds"])  # runs per cell
        bases = _expected_cells(league_dir, m["name"]) or []  # the cells in run order
        for p in sorted(tdir.glob("run-*.nc")):
            g = int(p.stem.split("-")[1]) // runs  # the cell of run-ID
            if g >= len(bases):
                continue
            case = bases[g].split("--")[0]
            with xr.open_dataset(p) as ds:
                if signal in ds:
                    v = ds[signal].values
                    v = v if v.ndim == 1 else np.max(np.abs(v.reshape(v.shape[0], -1)), axis=1)
                    traces.setdefault(case, {})[m["name"]] = (ds["time"].values, v)
    cases = list(traces)
    if not cases:
        return []
    title = f"{signal} of every method, seed {meta.get('trace_seed', 0)}, first level"
    fig, axes = new_figure(len(cases), 1, width=7.0, height=1.0 + 2.0 * len(cases), title=title)
    for ax, case in zip(axes[:, 0], cases, strict=True):
        for name, (t, v) in traces[case].items():
            ax.plot(t, np.maximum(v, 1e-6), lw=0.8, label=name)
        ax.set_yscale("log")
        ax.axhline(limit, color="tab:red", lw=0.6)
        ax.set_ylabel(f"{case} [{units}]", fontsize=7)
    axes[-1, 0].set_xlabel("time [s]")
    axes[0, 0].legend(loc="upper right", fontsize=6, ncol=2)
    return [save_figure(fig, out / "trajectories.png")]


# ---------------------------------------------------------------------------------------------- page
#: scores per per-fault table: each is a median and a p95 column, so that a table of a case fits a
#: 1,280 px window whatever the league scores (method, runs, diverged, pass rate and 4 x 2 numbers)
SCORES_PER_TABLE = 4


def _per_fault(cells: pd.DataFrame, units: dict[str, str]) -> list[dict[str, Any]]:
    """The per-fault tables of the page: per (level, case) the rows and the tables they are split into
    (:data:`SCORES_PER_TABLE` scores each; the first one with runs, diverged and pass rate)."""
    scores = [s for s in SCORES if f"{s}_median" in cells]
    groups = [scores[k : k + SCORES_PER_TABLE] for k in range(0, len(scores), SCORES_PER_TABLE)]
    unit = {s: units.get(f"{s}_median", "") for s in scores}
    heading = {s: f"{s} [{unit[s]}]" if unit[s] not in ("", "1") else s for s in scores}
    parts = []
    for k, group in enumerate(groups or [[]]):
        counts = [("method", "method")]
        if k == 0:
            counts += [("runs", "runs"), ("failed", "diverged"), ("pass_rate", "pass rate")]
        parts.append(
            {
                "counts": [label for _, label in counts],
                "scores": [{"label": heading[s]} for s in group],
                "columns": [key for key, _ in counts]
                + [f"{s}_{stat}" for s in group for stat in ("median", "p95")],
            }
        )
    return [
        {"level": level, "case": case, "rows": g.to_dict("records"), "parts": parts}
        for (level, case), g in cells.groupby(["level", "case"], sort=False)
    ]


def _tuned_text(result: dict[str, Any] | None) -> str:
    """One line for the leaderboard's "tuned" column: gains, objective and held-out pass rate."""
    if result is None:
        return "not tuned"

    def _fmt(v: Any) -> str:
        return f"{v:.3g}" if isinstance(v, int | float) and math.isfinite(v) else "-"

    def pass_rate(runs: dict[str, Any]) -> str:  # of the tuned and the paper gains on some runs
        tuned, paper = runs.get("tuned", {}), runs.get("paper", {})
        return (
            f"pass rate {_fmt(tuned.get('pass_rate'))} (paper {_fmt(paper.get('pass_rate'))}, "
            f"{tuned.get('runs', '?')} runs)"
        )

    obj = result.get("objective", {})
    name, units = obj.get("metric", "objective"), obj.get("units", "")
    score = f"{name}_{obj.get('statistic', 'mean')}"
    ho = result.get("holdout", {})
    gains = ", ".join(
        f"{str(k).rpartition('.')[2]} {_fmt(v)}" for k, v in result.get("tuned_gains", {}).items()
    )
    fresh = result.get("fresh")
    return (
        f"{gains}; {obj.get('statistic', 'mean')} {name} {_fmt(ho.get('tuned', {}).get(score))} "
        f"{units} (paper {_fmt(ho.get('paper', {}).get(score))}); held-out {pass_rate(ho)}"
        + (f"; fresh-seed {pass_rate(fresh)}" if fresh else "")
    )


def tuned_column(rank: dict[str, list[dict[str, Any]]], tuned_dir: str | Path) -> int:
    """Give every ranking row a ``"tuned"`` entry (:func:`_tuned_text` of the method's tuning at that
    level in ``tuned_dir``, or "not tuned") and ``"tuning"`` (the result's summary or None); returns
    how many rows have a tuning.

    Parameters
    ----------
    rank : dict
        From :func:`ranking` (changed in place).
    tuned_dir : str or Path
        A directory of ``formation-ftc tune`` results (``METHOD--LEVEL.json``).

    Returns
    -------
    int
        Rows with a tuning result.

    Examples
    --------
    >>> rank = {"limited": [{"method": "lqr"}]}
    >>> tuned_column(rank, "/nonexistent"), rank["limited"][0]["tuned"]
    (0, 'not tuned')
    """
    from formation_ftc.league.tuning import load_tunings

    results = load_tunings(tuned_dir)
    n = 0
    for level, rows in rank.items():
        for r in rows:
            res = results.get((str(r["method"]), str(level)))
            r["tuned"] = _tuned_text(res)
            r["tuning"] = None
            if res is not None:
                r["tuning"] = {
                    "gains": res.get("tuned_gains"),
                    "paper_gains": res.get("paper_gains"),
                    "objective": res.get("objective", {}).get("metric"),
                    "holdout": {k: res.get("holdout", {}).get(k) for k in ("paper", "tuned")},
                    "fresh": {k: (res.get("fresh") or {}).get(k) for k in ("paper", "tuned")},
                    "optimiser": res.get("optimiser", {}).get("name"),
                }
                n += 1
    return n


def _page(
    meta,
    cells: pd.DataFrame,
    rank: dict,
    wins: list,
    figures: list[Path],
    fdi: dict[str, Any] | None = None,
    units: dict[str, str] | None = None,
    seeds: str = "",
    incomplete: str | None = None,
) -> str:
    """The leaderboard page (template ``report/templates/league.html.j2``); ``units``: of the cell
    columns (:func:`_units`), shown in the per-fault tables' headers."""
    metric, limit, req_units = _requirement(meta)
    cost = _cost(cells)
    median = f"median {metric} [{req_units}]"
    ranking_tables = []
    confidence = _has_confidence(rank)
    for level, rows in rank.items():
        columns = _ranking_columns(rows, median, cost, confidence, "tuned (formation-ftc tune)")
        ranking_tables.append((level, _display_rows(rows, metric), columns))
    battery = meta["battery"]
    return render(
        "league.html.j2",
        title=f"league {meta['name']}",
        heading=f"formation-ftc league: {meta['name']}",
        subtitle="",
        intro={
            "version": meta["version"],
            "hash": str(meta["hash"])[:16],
            "battery": battery["name"],
            "battery_version": battery["version"],
            "battery_hash": str(battery.get("sha256", ""))[:16],
            "seeds": seeds or f"{meta['seeds']} seed(s) per cell",
            "quick": bool(meta.get("quick")),
        },
        incomplete=incomplete,
        metric=metric,
        limit=limit,
        units=req_units,
        ranking=ranking_tables,
        ranking_note=st.method_note() if confidence else None,
        identification_note=IDENTIFICATION_NOTE,
        winners=wins,
        winner_columns=[
            ("level", "level"),
            ("case", "fault case"),
            ("method", "best method"),
            ("pass_rate", "pass rate"),
            (f"{metric}_median", median),
        ],
        fdi=None if fdi is None else _fdi_tables(fdi),
        per_fault=_per_fault(cells, units or {}),
        scores_per_table=SCORES_PER_TABLE,
        figures=[{"alt": p.stem, "src": _data_uri(p)} for p in figures],  # embedded PNG files
        methods=meta["methods"],
        method_columns=[
            ("name", "name"),
            ("label", "law"),
            ("reference", "source"),
            ("gain_rule", "gains"),
        ],
        definition=meta["definition"],
        method_files=list(meta.get("method_files", {}).items()),
        provenance=[{"key": k, "value": v} for k, v in (meta.get("provenance") or {}).items()],
    )


def _ranking_columns(
    rows: list[dict[str, Any]],
    median: str,
    cost: tuple[str, str] | None,
    confidence: bool,
    tuned: str,
) -> list[tuple[str, str]]:
    """The (key, label) columns of a level's ranking table (page and Markdown): ``median`` labels the
    requirement metric's median, ``tuned`` the tuned column (when the rows have one)."""
    ci = " [95 % CI]" if confidence else ""
    return [
        ("rank_text", "rank"),
        ("method", "method"),
        ("pass_rate_text", f"pass rate{ci}"),
        ("median_text", f"{median}{ci}"),
        *([(f"{cost[0]}_median", f"median {cost[1]}")] if cost else []),
        *([("versus_text", "vs. row above: Holm p (test)")] if confidence else []),
        ("failed", "diverged"),
        ("runs", "runs"),
        *([("tuned", tuned)] if rows and "tuned" in rows[0] else []),
    ]


def _interval_text(v: Any, low: Any, high: Any, fixed: bool = False) -> str:
    """``0.700 [0.62, 0.77]`` (``fixed``: a fraction, 3 and 2 decimals) or ``1.23 [1.1, 1.4]`` (3
    significant digits); the value alone when there is no interval, "-" for no value.

    Examples
    --------
    >>> _interval_text(0.7, 0.6213, 0.7712, fixed=True), _interval_text(1.234, 1.1, None)
    ('0.700 [0.62, 0.77]', '1.23')
    """

    def ok(x: Any) -> bool:
        return isinstance(x, int | float) and math.isfinite(x)

    if not ok(v):
        return "-"
    text = f"{v:.3f}" if fixed else fmt(float(v))
    if not (ok(low) and ok(high)):
        return text
    if fixed:
        return f"{text} [{low:.2f}, {high:.2f}]"
    return f"{text} [{fmt(float(low))}, {fmt(float(high))}]"


def _versus_text(r: dict[str, Any]) -> str:
    """The comparison of a ranking row with the row above: ``p 0.012 (McNemar)`` (Holm-adjusted)."""
    p = r.get("p_adjusted")
    if not isinstance(p, int | float) or not math.isfinite(p):
        return "-"
    test = str(r.get("test"))
    name = {"mcnemar": "McNemar", "wilcoxon": "Wilcoxon"}.get(test, test)
    return f"{'<0.001' if p < 0.001 else format(p, '.3f')} ({name})"


def _display_rows(rows: list[dict[str, Any]], metric: str) -> list[dict[str, Any]]:
    """Ranking rows with their text cells: ``rank_text`` ("3="), ``pass_rate_text`` and
    ``median_text`` (value and 95 % interval), ``versus_text`` (adjusted p of the comparison with the
    row above, and its test)."""
    median = f"{metric}_median"
    return [
        {
            **r,
            "rank_text": str(r.get("rank_display", r.get("rank"))),
            "pass_rate_text": _interval_text(
                r.get("pass_rate"), r.get("pass_rate_low"), r.get("pass_rate_high"), fixed=True
            ),
            "median_text": _interval_text(
                r.get(median), r.get(f"{median}_low"), r.get(f"{median}_high")
            ),
            "versus_text": _versus_text(r),
        }
        for r in rows
    ]


def _has_confidence(rank: dict[str, list[dict[str, Any]]]) -> bool:
    return any("pass_rate_low" in r for rows in rank.values() for r in rows)


def ranking_frame(rank: dict[str, list[dict[str, Any]]]) -> pd.DataFrame:
    """The ranking of every level as one table (``level`` first, then the rows' scalar columns; the
    nested ``tuning`` summary left out), as ``leaderboard/ranking.parquet`` stores it.

    Parameters
    ----------
    rank : dict
        From :func:`ranking`.

    Returns
    -------
    pandas.DataFrame
        One row per (level, method).

    Examples
    --------
    >>> ranking_frame({"limited": [{"method": "lqr", "rank": 1, "tuning": None}]}).columns.tolist()
    ['level', 'rank', 'method']
    """
    records = [
        {"level": str(level), **{k: v for k, v in r.items() if k != "tuning"}}
        for level, rows in rank.items()
        for r in rows
    ]
    frame = pd.DataFrame(records)
    first = [c for c in ("level", "rank", "rank_display", "tied", "method") if c in frame]
    frame = frame[first + [c for c in frame.columns if c not in first]]
    # the comparison columns are null on a level's first row: nullable integers and booleans
    nullable = {"pairs": "Int64", "only_above_passed": "Int64", "only_this_passed": "Int64"}
    nullable["separated"] = "boolean"
    return frame.astype({c: t for c, t in nullable.items() if c in frame})


def _md_table(rows: list[dict[str, Any]], cols: list[tuple[str, str]]) -> str:
    head = "| " + " | ".join(label for _, label in cols) + " |"
    sep = "|" + "|".join("---" for _ in cols) + "|"
    body = [
        "| " + " | ".join(fmt(r.get(k)).replace("|", "/") for k, _ in cols) + " |" for r in rows
    ]
    return "\n".join([head, sep, *body])


def markdown_summary(board: dict[str, Any]) -> str:
    """The ranking per level and the best method per fault case as Markdown tables (for a README)."""
    req = board["requirement"]
    metric = req["metric"]
    cells = pd.DataFrame(board["cells"])
    cost = _cost(cells) if len(cells) else None
    comp = board.get("completeness")
    note = incomplete_note(comp) if comp else None
    seeds = seeds_text(comp) if comp else f"{board['seeds']} seeds per cell"
    out = [
        *([f"**{note}**", ""] if note else []),
        f"League `{board['league']}` (definition version {board['version']}), fault battery "
        f"{board['battery']['name']} (version {board['battery']['version']}), {seeds}; "
        f"requirement {metric} <= {req['max']:g} {req['units']}.",
    ]
    confidence = _has_confidence(board["ranking"])
    for level, rows in board["ranking"].items():
        cols = _ranking_columns(rows, f"median {metric}", cost, confidence, "tuned")
        out += ["", f"**{level}**", "", _md_table(_display_rows(rows, metric), cols)]
    if confidence:
        out += ["", st.method_note()]
    if board.get("resolution"):
        out += ["", resolution_text(board["resolution"]) + "."]
    best = {(w["case"], w["level"]): w for w in (_winners(cells, metric) if len(cells) else [])}
    levels = list(board["ranking"])
    rows = [
        {"case": case, **{lv: _best_text(best.get((case, lv))) for lv in levels}}
        for case in dict.fromkeys(r["case"] for r in board["cells"])
    ]
    columns = [("case", "fault case"), *[(lv, lv) for lv in levels]]
    out += ["", "Best method per fault case (pass rate):", "", _md_table(rows, columns)]
    if board.get("fdi") is not None:
        fdi = _fdi_tables(board["fdi"])
        out += ["", "**FDI**", "", fdi["note"]]
        if fdi["rows"]:
            out += ["", _md_table(fdi["rows"], fdi["columns"])]  # None (not a number): "-"
        if fdi["identification"]:
            out += ["", "**Fault identification**", "", IDENTIFICATION_NOTE, ""]
            out += [_md_table(fdi["identification"], fdi["identification_columns"])]
    return "\n".join(out) + "\n"


def _best_text(best: dict[str, Any] | None) -> str:
    """A cell of the Markdown table of the best method per fault case: the winner and its pass rate."""
    if best is None:
        return "-"
    if best["pass_rate"] > 0:
        return f"{best['method']} ({best['pass_rate']:.2f})"
    return f"none passes (lowest median: {best['method']})"


def resolution_text(record: dict[str, Any]) -> str:
    """What ``--until-resolved`` did, in one paragraph (also under the league's Markdown board)."""
    why = {
        "resolved": "every adjacent pair separated or tied",
        "budget": "budget spent, pairs still open",
    }[record["stopped"]]
    verdicts = (v for vs in record["blocks"][-1]["verdicts"].values() for v in vs)
    counts = Counter(
        "separated on the metric" if v.get("by") == "metric" else v["verdict"] for v in verdicts
    )
    pairs = ", ".join(f"{n} {k}" for k, n in sorted(counts.items()))
    return (
        f"until resolved: stopped at {record['seeds']} seeds per cell ({why}: {pairs}); "
        f"{record['runs']} runs against {record['fixed_runs']} for the league's fixed "
        f"{record['fixed_seeds']} seeds ({record['saved_runs']} saved); blocks of {record['block']} "
        f"seeds, a tie excludes a pass-rate difference of {record['margin']:g} at power "
        f"{record['power']:g}"
    )


def _run_units(league_dir: Path, meta: dict[str, Any]) -> dict[str, str]:
    """Units of the run columns, as the methods' campaign chunks store them (:mod:`formation_ftc.parquet_units`)."""
    from formation_ftc.campaign.storage import CampaignStore

    units: dict[str, str] = {}
    for m in meta["methods"]:
        cdir = league_dir / m["name"] / "campaign"
        if cdir.is_dir():
            units.update(CampaignStore.read(cdir).units())
    return units


def _units(frame: pd.DataFrame, run_units: dict[str, str]) -> dict[str, str]:
    """Units of a cell or ranking column: a score's median, p95 and interval bounds in the score's
    unit; counts, rates, statistics and p-values dimensionless."""
    units: dict[str, str] = {}
    for name in map(str, frame.columns):
        score = re.fullmatch(r"(.+)_(median|p95)(_low|_high)?", name)
        if score is None:
            units[name] = "1"
        elif f"metric:{score[1]}" in run_units:
            units[name] = run_units[f"metric:{score[1]}"]
    return units


def write_leaderboard(
    league_dir: str | Path, plots: bool = True, tuned: str | Path | None = None
) -> dict[str, Any]:
    """Write the leaderboard files of a league directory; returns the leaderboard dictionary.

    ``tuned``: a directory of ``formation-ftc tune`` results (default ``league_dir/tuned`` when it
    exists): the ranking rows get a "tuned" column next to the paper-gain results (gains, objective,
    held-out pass rate; "not tuned" for a method without a result)."""
    league_dir = Path(league_dir)
    meta, runs = load_league_results(league_dir)
    cells = cell_table(meta, runs)
    rank = ranking(meta, cells, runs)
    tuned_dir = Path(tuned) if tuned is not None else league_dir / "tuned"
    if tuned is not None or tuned_dir.is_dir():
        tuned_column(rank, tuned_dir)
    wins = winners(meta, cells)
    fdi = fdi_table(meta, runs)
    comp = completeness(meta, runs, league_dir)
    out = league_dir / "leaderboard"
    out.mkdir(parents=True, exist_ok=True)
    figures = [*_pareto(meta, cells, out), *_trajectories(meta, league_dir, out)] if plots else []
    metric, limit, units = _requirement(meta)
    board = {
        "league": meta["name"],
        "version": meta["version"],
        "hash": meta["hash"],
        "seeds": meta["seeds"],
        "quick": meta.get("quick", False),
        "complete": comp["complete"],
        "completeness": comp,
        "battery": meta["battery"],
        "levels": meta["levels"],
        "requirement": {"metric": metric, "max": limit, "units": units},
        "provenance": meta.get("provenance"),
        "ranking": rank,
        "ranking_method": st.method_note(),
        "winners": wins,
        "cells": cells.to_dict("records"),
        "fdi": fdi,
    }
    resolution = league_dir / "resolution.json"
    if resolution.is_file() and meta.get("blocks"):
        with contextlib.suppress(OSError, ValueError):  # damaged: the board without it
            board["resolution"] = json.loads(resolution.read_text(encoding="utf-8"))
    atomic_write(out / "leaderboard.json", json.dumps(jsonable(board), indent=1))
    run_units = _run_units(league_dir, meta)
    cell_units = _units(cells, run_units)
    # the completeness also in the Parquet files' key-value metadata (a file read on its own says it)
    kv = {"formation_ftc.league.completeness": json.dumps(comp)}
    write_parquet(cells, out / "cells.parquet", cell_units, metadata=kv)
    write_parquet(runs, out / "runs.parquet", run_units, metadata=kv)
    frame = ranking_frame(rank)
    method = {"formation_ftc.league.ranking_method": st.method_note()}
    write_parquet(frame, out / "ranking.parquet", _units(frame, run_units), metadata=kv | method)
    page = _page(
        meta, cells, rank, wins, figures, fdi, cell_units, seeds_text(comp), incomplete_note(comp)
    )
    atomic_write(out / "index.html", page)
    atomic_write(out / "leaderboard.md", markdown_summary(jsonable(board)))
    return board
