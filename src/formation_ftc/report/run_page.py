"""The page ``formation-ftc run`` writes next to a result: standard figures drawn from the dataset's
declared signals, the method's own figures, an optional interactive 3-D trajectory, one ``index.html``.

Standard figures (each only when the result has the signals it needs):

* ``run_position.png``: ``position`` [m] per axis, one line per spacecraft;
* ``run_tracking_error.png``: Euclidean norm of every tracking-error signal (``position_error``,
  ``tracking_error``, ``position_tracking_error``, ``velocity_tracking_error``, ``attitude_error`` ...)
  per spacecraft;
* ``run_control.png``: ``command`` (dashed) vs ``applied`` (solid) per axis, spacecraft 1 (the one faults
  usually hit first) and the norm for every spacecraft;
* ``run_fault.png``: ``fault`` (or ``fault_acceleration``, whichever has the estimate's units; solid) vs
  ``fault_estimate`` (dashed) per axis.

The page (template ``report/templates/run.html.j2``) loads nothing from the network: figures are
referenced by relative file name; the 3-D view (plotly, only with the ``interactive`` extra installed)
loads the nearest ``plotly.min.js`` at or above the page's directory -- one copy serves a whole tree of
runs -- and writes one next to the page only when there is none.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from formation_ftc.exitcodes import jsonable

__all__ = ["standard_figures", "write_run_page", "ERROR_SIGNALS"]

#: Signal names read as tracking errors (in this order, those present).
ERROR_SIGNALS = (
    "position_error",
    "position_tracking_error",
    "tracking_error",
    "velocity_tracking_error",
    "attitude_error",
    "track_error",
    "sync_error",
    "formation_error",
)
_MAX_POINTS = 4000


def _decimated(ds):
    n = ds.sizes.get("time", 0)
    return ds.isel(time=slice(None, None, max(1, n // _MAX_POINTS))) if n > _MAX_POINTS else ds


def _per_spacecraft(var):
    """(labels, 2-D list of (time,) or (time, k) arrays) with the spacecraft dimension split off."""
    if "spacecraft" in var.dims:
        return [f"spacecraft {int(s)}" for s in var["spacecraft"].values], [
            var.sel(spacecraft=s) for s in var["spacecraft"].values
        ]
    return ["all"], [var]


def _pairs(a, b):
    """(label, part of ``a``, part of ``b``) per spacecraft of two variables of the same dims."""
    (labels, parts_a), (_, parts_b) = _per_spacecraft(a), _per_spacecraft(b)
    return zip(labels, parts_a, parts_b, strict=True)


def _norm_over_rest(v) -> np.ndarray:
    a = np.asarray(v.values, dtype=float)
    return np.linalg.norm(a.reshape(a.shape[0], -1), axis=1) if a.ndim > 1 else np.abs(a)


def _axes_of(var) -> list:
    last = [d for d in var.dims if d not in ("time", "spacecraft")]
    return list(var[last[0]].values) if len(last) == 1 else []


def standard_figures(ds, out_dir: Path | str) -> list[Path]:
    """Write the standard figures of a result into ``out_dir``; returns their paths (time in s)."""
    from formation_ftc.plotting import new_figure, save_figure

    out_dir = Path(out_dir)
    ds = _decimated(ds)
    t = np.asarray(ds["time"].values, dtype=float) if "time" in ds.coords else None
    if t is None:
        return []
    paths = []
    if "position" in ds and len(_axes_of(ds["position"])) >= 1:
        var = ds["position"]
        comps = _axes_of(var)
        fig, axes = new_figure(
            len(comps),
            1,
            title=f"Positions ({var.attrs.get('frame', '')} frame)".replace(" ( frame)", ""),
        )
        for k, c in enumerate(comps):
            for lab, v in zip(*_per_spacecraft(var), strict=True):
                axes[k, 0].plot(t, v.sel({var.dims[-1]: c}).values, label=lab)
            axes[k, 0].set_ylabel(f"{c} [{var.attrs.get('units', '')}]")
        axes[0, 0].legend(loc="best")
        axes[-1, 0].set_xlabel("time [s]")
        paths.append(save_figure(fig, out_dir / "run_position.png"))
    errors = [
        n
        for n in ERROR_SIGNALS  # a stacked vector of mixed units has no meaningful norm
        if n in ds and "time" in ds[n].dims and "component_units" not in ds[n].attrs
    ]
    if errors:
        fig, axes = new_figure(len(errors), 1, title="Tracking errors (Euclidean norm)")
        for k, name in enumerate(errors):
            var = ds[name]
            for lab, v in zip(*_per_spacecraft(var), strict=True):
                axes[k, 0].plot(t, _norm_over_rest(v), label=lab)
            axes[k, 0].set_ylabel(f"|{name}| [{var.attrs.get('units', '')}]")
            axes[k, 0].set_title(var.attrs.get("long_name", name))
        axes[0, 0].legend(loc="best")
        axes[-1, 0].set_xlabel("time [s]")
        paths.append(save_figure(fig, out_dir / "run_tracking_error.png"))
    if "command" in ds and "applied" in ds and ds["command"].dims == ds["applied"].dims:
        cmd, app = ds["command"], ds["applied"]
        comps = _axes_of(cmd)
        fig, axes = new_figure(
            len(comps) + 1, 1, title="Control: commanded (dashed) vs applied (solid)"
        )
        first = {"spacecraft": cmd["spacecraft"].values[0]} if "spacecraft" in cmd.dims else {}
        for k, c in enumerate(comps):
            sel = {**first, cmd.dims[-1]: c}
            axes[k, 0].plot(t, cmd.sel(sel).values, "--", label="commanded")
            axes[k, 0].plot(t, app.sel(sel).values, "-", label="applied")
            sc = f"spacecraft {int(first['spacecraft'])}, " if first else ""
            axes[k, 0].set_ylabel(f"{sc}{c} [{cmd.attrs.get('units', '')}]")
        for j, (lab, vc, va) in enumerate(_pairs(cmd, app)):
            color = f"C{j % 8}"
            axes[-1, 0].plot(t, _norm_over_rest(vc), "--", color=color)
            axes[-1, 0].plot(t, _norm_over_rest(va), "-", color=color, label=lab)
        axes[-1, 0].set_ylabel(f"norm [{cmd.attrs.get('units', '')}]")
        axes[0, 0].legend(loc="best")
        axes[-1, 0].legend(loc="best")
        axes[-1, 0].set_xlabel("time [s]")
        paths.append(save_figure(fig, out_dir / "run_control.png"))
    truth = [
        n
        for n in ("fault", "fault_acceleration")
        if n in ds
        and "fault_estimate" in ds
        and ds[n].dims == ds["fault_estimate"].dims
        and ds[n].attrs.get("units") == ds["fault_estimate"].attrs.get("units")
    ]
    if truth:  # the true fault in the estimate's units
        f, fh = ds[truth[0]], ds["fault_estimate"]
        comps = _axes_of(f) or [None]
        fig, axes = new_figure(len(comps), 1, title="Fault (solid) vs its estimate (dashed)")
        for k, c in enumerate(comps):
            sel = {f.dims[-1]: c} if c is not None else {}
            for j, (lab, vf, ve) in enumerate(_pairs(f.sel(sel), fh.sel(sel))):
                color = f"C{j % 8}"
                axes[k, 0].plot(
                    t,
                    _norm_over_rest(vf) if vf.ndim > 1 else vf.values,
                    "-",
                    color=color,
                    label=lab,
                )
                axes[k, 0].plot(
                    t, _norm_over_rest(ve) if ve.ndim > 1 else ve.values, "--", color=color
                )
            axes[k, 0].set_ylabel(f"{'' if c is None else c} [{f.attrs.get('units', '')}]")
        axes[0, 0].legend(loc="best")
        axes[-1, 0].set_xlabel("time [s]")
        paths.append(save_figure(fig, out_dir / "run_fault.png"))
    return paths


def _trajectory(ds, out_dir: Path) -> dict[str, Any] | None:
    """Interactive 3-D trajectory (plotly; the page loads the report tree's one copy of plotly's
    bundle, :func:`formation_ftc.report.html.plotly_script`), a note saying why there is none, or None
    when the result has no 3-D positions."""
    if "position" not in ds or _axes_of(ds["position"])[:3] != ["x", "y", "z"]:
        return None
    try:
        import plotly.graph_objects as go
    except ImportError:
        return {
            "unavailable": "Interactive 3-D trajectory unavailable: plotly is not installed "
            "(install the interactive extra: pip install 'formation-ftc[interactive]')."
        }
    from markupsafe import Markup

    from formation_ftc.report.html import plotly_script

    var = _decimated(ds)["position"]
    fig = go.Figure()
    for lab, v in zip(*_per_spacecraft(var), strict=True):
        a = np.asarray(v.values, dtype=float)
        fig.add_trace(go.Scatter3d(x=a[:, 0], y=a[:, 1], z=a[:, 2], mode="lines", name=lab))
    units = var.attrs.get("units", "m")
    fig.update_layout(
        scene={
            "xaxis_title": f"x [{units}]",
            "yaxis_title": f"y [{units}]",
            "zaxis_title": f"z [{units}]",
        },
        margin={"l": 0, "r": 0, "t": 30, "b": 0},
        title=f"Trajectory ({var.attrs.get('frame', '')})",
    )
    return {
        "unavailable": "",
        "src": plotly_script(out_dir),
        "html": Markup(fig.to_html(full_html=False, include_plotlyjs=False, div_id="trajectory3d")),
    }


def write_run_page(
    out_dir: Path | str,
    ds,
    metrics: Mapping[str, Any],
    figures: Sequence[Path | str],
    units: Mapping[str, str] | None = None,
    *,
    include_3d: bool = True,
) -> Path:
    """Write ``out_dir/index.html``: title, metrics table (with units), figures and, with
    ``include_3d``, the interactive 3-D trajectory (which loads the nearest ``plotly.min.js`` at or
    above ``out_dir``, written into ``out_dir`` when there is none)."""
    from formation_ftc.atomic import atomic_write
    from formation_ftc.report.templating import render

    out_dir = Path(out_dir)
    name = str(ds.attrs.get("scenario_name", ""))
    units = dict(units or {})
    meta = {
        k: ds.attrs.get(k, "") for k in ("method", "seed", "git_commit", "created_utc", "diverged")
    }
    page = render(
        "run.html.j2",
        title=f"{name} - formation-ftc run",
        heading=name,
        subtitle=str(ds.attrs.get("title", "")),
        meta={k: jsonable(v) for k, v in meta.items()},
        metrics=[
            (str(k), v, units.get(k, ""))
            for k, v in metrics.items()
            if isinstance(v, int | float) and not isinstance(v, bool)
        ],
        figures=[{"src": Path(p).name, "alt": Path(p).stem} for p in figures],
        trajectory=_trajectory(ds, out_dir) if include_3d else None,
    )
    return atomic_write(out_dir / "index.html", page)
