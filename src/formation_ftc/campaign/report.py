"""Summary statistics and sensitivity plots of a finished (or partly finished) campaign.

``formation-ftc campaign report DIR`` prints, per metric, the number of successful runs, mean, std
(ddof = 1), min, 5/25/50/75/95th percentiles, max and the failure rate (failed runs plus runs whose
metric is not finite), overall and per swept value (grid point); a metric that one of several base
scenarios does not return is summarised over the other bases' runs only. It writes ``DIR/report/summary.json``,
``DIR/report/summary.csv``, one sensitivity figure per sampled numeric input (metric vs input, failed
runs marked on the axis) and one figure per swept field (median and 5-95 % band vs the swept value).
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from formation_ftc.campaign.storage import CampaignStore
from formation_ftc.exitcodes import jsonable

__all__ = ["summarize", "write_report", "field_unit", "PERCENTILES"]

PERCENTILES = (5, 25, 50, 75, 95)
_MAX_METRICS_PER_FIGURE = 6


def _stats(values: pd.Series, n_runs: int) -> dict[str, Any]:
    v = pd.to_numeric(values, errors="coerce").to_numpy(dtype=float)
    finite = v[np.isfinite(v)]
    out: dict[str, Any] = {
        "n_ok": int(finite.size),
        "n_runs": int(n_runs),
        "failure_rate": float(1 - finite.size / n_runs) if n_runs else float("nan"),
    }
    out.update(
        dict.fromkeys(("mean", "std", "min", "max", *(f"p{p}" for p in PERCENTILES)), np.nan)
    )
    if finite.size:
        out.update(
            mean=float(finite.mean()),
            std=float(finite.std(ddof=1)) if finite.size > 1 else float("nan"),
            min=float(finite.min()),
            max=float(finite.max()),
        )
        for p, q in zip(PERCENTILES, np.percentile(finite, PERCENTILES), strict=True):
            out[f"p{p}"] = float(q)
    return out


def _metric_columns(df: pd.DataFrame) -> list[str]:
    return [c for c in df.columns if c.startswith("metric:")]


def _bases_returning(df: pd.DataFrame) -> dict[str, set] | None:
    """Per metric column, the base scenarios that return it (some successful run has a finite value);
    None for a single-base campaign (every run counts for every metric)."""
    if "scenario" not in df.columns or df["scenario"].nunique() < 2:
        return None
    ok = (df["status"] == "ok").to_numpy()
    out = {}
    for c in _metric_columns(df):
        finite = np.isfinite(pd.to_numeric(df[c], errors="coerce").to_numpy(dtype=float)) & ok
        out[c] = set(df.loc[finite, "scenario"])
    return out


def _metric_stats(df: pd.DataFrame, bases: dict[str, set] | None) -> dict[str, dict[str, Any]]:
    """:func:`_stats` of every metric over the runs it applies to: in a campaign over several base
    scenarios, a base none of whose successful runs has a finite value of a metric does not return it
    (e.g. ``b_hat`` is SIR-FTC's, not Theorem 1's), and its runs are left out of that metric instead
    of counting as failures (``bases`` from :func:`_bases_returning` of the whole table)."""
    out = {}
    for c in _metric_columns(df):
        sub = df if bases is None else df[df["scenario"].isin(bases[c])]
        if len(sub):
            out[c[len("metric:") :]] = _stats(sub[c], len(sub))
    return out


def summarize(df: pd.DataFrame, manifest: dict[str, Any]) -> dict[str, Any]:
    """Statistics per metric, overall and per swept value (see module docstring)."""
    n = len(df)
    failed = int((df["status"] != "ok").sum()) if n else 0
    bases = _bases_returning(df) if n else None
    out: dict[str, Any] = {
        "campaign": manifest.get("campaign"),
        "spec_hash": manifest.get("spec_hash"),
        "runs_total": int(manifest.get("n_runs", n)),
        "runs_done": n,
        "runs_failed": failed,
        "failure_rate": failed / n if n else float("nan"),
        "metrics": _metric_stats(df, bases),
        "by_swept_value": {},
        "failures": df.loc[df["status"] != "ok", ["run_id", "diagnostic"]]
        .head(20)
        .to_dict("records")
        if n
        else [],
    }
    for col in manifest.get("swept", []):
        if col not in df.columns:
            continue
        groups = {}
        for value, sub in df.groupby(col, sort=True):
            groups[str(value)] = {
                "runs": int(len(sub)),
                "failed": int((sub["status"] != "ok").sum()),
                "metrics": _metric_stats(sub, bases),
            }
        out["by_swept_value"][col.removeprefix("input:")] = groups
    return out


def _table_rows(summary: dict[str, Any]) -> pd.DataFrame:
    rows = []
    for m, st in summary["metrics"].items():
        rows.append({"group": "all", "value": "", "metric": m, **st})
    for field, groups in summary["by_swept_value"].items():
        for value, g in groups.items():
            for m, st in g["metrics"].items():
                rows.append({"group": field, "value": value, "metric": m, **st})
    return pd.DataFrame(rows)


def field_unit(manifest: dict[str, Any], path: str) -> str:
    """Unit of a scenario field from its schema description ('... [m]') or '' when unknown."""
    try:
        from formation_ftc.config.base import field_info
        from formation_ftc.registry import get_method

        info = field_info(get_method(manifest["plan"]["methods"][0]).schema, path)
        desc = (info.description or "") if info is not None else ""
        m = re.findall(r"\[([^\]]+)\]", desc)
        return m[-1] if m else ""
    except Exception:  # noqa: BLE001 - a label is cosmetic
        return ""


def _sensitivity_figures(df: pd.DataFrame, manifest: dict[str, Any], out: Path) -> list[Path]:
    from formation_ftc.plotting import new_figure

    paths: list[Path] = []
    metrics = _metric_columns(df)[:_MAX_METRICS_PER_FIGURE]
    numeric = manifest.get("input_columns", {})
    swept = [c for c in manifest.get("swept", []) if c in df.columns]
    colour_by = swept[0] if swept else None
    if not metrics:
        return paths
    for col in manifest.get("sampled", []):
        if col not in df.columns or not numeric.get(col, False):
            continue
        path = col.removeprefix("input:")
        fig, axes = new_figure(
            len(metrics), 1, sharex=True, title=f"{manifest.get('campaign')}: sensitivity to {path}"
        )
        x_all = pd.to_numeric(df[col], errors="coerce")
        ok = df["status"] == "ok"
        for ax, m in zip(axes[:, 0], metrics, strict=False):
            y = pd.to_numeric(df[m], errors="coerce")
            groups = df.groupby(colour_by) if colour_by else [("all runs", df)]
            for value, sub in groups:
                idx = sub.index[ok[sub.index]]
                label = f"{colour_by.removeprefix('input:')} = {value}" if colour_by else str(value)
                ax.scatter(x_all[idx], y[idx], s=8, alpha=0.7, label=label)
            bad = df.index[~ok]
            if len(bad):
                lo = np.nanmin(y[ok]) if ok.any() else 0.0
                ax.scatter(
                    x_all[bad],
                    np.full(len(bad), lo),
                    marker="x",
                    color="k",
                    s=14,
                    label=f"failed ({len(bad)})",
                )
            ax.set_ylabel(m.removeprefix("metric:"))
        paths.append(_save(fig, axes, _axis_label(manifest, path), out / "sensitivity", path))
    return paths


def _swept_figures(summary: dict[str, Any], manifest: dict[str, Any], out: Path) -> list[Path]:
    from formation_ftc.plotting import new_figure

    paths = []
    for field, groups in summary["by_swept_value"].items():
        values = list(groups)
        metrics = (
            list(next(iter(groups.values()))["metrics"])[:_MAX_METRICS_PER_FIGURE] if groups else []
        )
        if not metrics:
            continue
        try:
            xs, xlabel = [float(v) for v in values], _axis_label(manifest, field)
        except ValueError:
            xs, xlabel = list(range(len(values))), field
        fig, axes = new_figure(
            len(metrics), 1, sharex=True, title=f"{manifest.get('campaign')}: {field} sweep"
        )
        for ax, m in zip(axes[:, 0], metrics, strict=False):
            q = {p: [groups[v]["metrics"][m][p] for v in values] for p in ("p5", "p50", "p95")}
            ax.fill_between(xs, q["p5"], q["p95"], alpha=0.25, label="5-95 %")
            ax.plot(xs, q["p50"], "o-", label="median")
            ax.set_ylabel(m)
        if not isinstance(xs[0], float):
            axes[-1, 0].set_xticks(xs, values, rotation=20)
        paths.append(_save(fig, axes, xlabel, out / "sweep", field))
    return paths


def _axis_label(manifest: dict[str, Any], path: str) -> str:
    """``path [unit]`` (:func:`field_unit`), or ``path`` when its unit is unknown."""
    unit = field_unit(manifest, path)
    return f"{path} [{unit}]" if unit else path


def _save(fig, axes, xlabel: str, prefix: Path, name: str) -> Path:
    """Label the bottom x axis, show the legend and save ``fig`` as ``PREFIX_NAME.png`` (``name`` made
    safe for a file name)."""
    from formation_ftc.plotting import save_figure

    axes[-1, 0].set_xlabel(xlabel)
    axes[0, 0].legend(loc="best")
    return save_figure(fig, Path(f"{prefix}_{re.sub(r'[^A-Za-z0-9_.-]', '_', name)}.png"))


def write_report(
    campaign_dir: str | Path, console=None, plots: bool = True
) -> tuple[dict[str, Any], list[Path]]:
    """Read ``campaign_dir``, print the tables, write ``report/`` (summary.json, summary.csv, PNGs)."""
    store = CampaignStore.read(campaign_dir)
    df = store.load_results()
    summary = summarize(df, store.manifest)
    out = Path(campaign_dir) / "report"
    out.mkdir(exist_ok=True)
    (out / "summary.json").write_text(json.dumps(jsonable(summary), indent=2))
    table = _table_rows(summary)
    table.to_csv(out / "summary.csv", index=False)
    figures: list[Path] = []
    if plots and len(df):
        figures += _sensitivity_figures(df, store.manifest, out)
        figures += _swept_figures(summary, store.manifest, out)
    if console is not None:
        _print(console, summary, table)
    return summary, figures


def _print(console, summary: dict[str, Any], table: pd.DataFrame) -> None:
    from rich.table import Table

    console.print(
        f"[bold]{summary['campaign']}[/]: {summary['runs_done']}/{summary['runs_total']} runs done, "
        f"{summary['runs_failed']} failed (failure rate {summary['failure_rate']:.3g})"
    )
    cols = ["group", "value", "metric", "n_ok", "failure_rate", "mean", "std", "p5", "p50", "p95"]
    t = Table(*cols)
    for _, r in table.iterrows():
        t.add_row(*[(f"{r[c]:.4g}" if isinstance(r[c], float) else str(r[c])) for c in cols])
    console.print(t)
    for f in summary["failures"][:5]:
        console.print(f"failed run {f['run_id']}: {f['diagnostic']}")
