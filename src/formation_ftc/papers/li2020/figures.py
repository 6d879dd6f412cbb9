"""Figures of Li et al. 2020 (Figs. 4-12) drawn from result datasets of its composed scenarios.

Each time history is drawn twice: a 0-100 s zoom (faults at 10/15/20 s, initial convergence) and the
whole horizon. Matplotlib is used only through :mod:`formation_ftc.plotting`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from formation_ftc.plotting import new_figure
from formation_ftc.report.run_page import finish_figure

__all__ = ["plot_errors", "plot_mu", "plot_adaptive", "plot_comparison", "plot_scenario"]

ZOOM = 100.0  # s
#: formation errors of Figs. 6, 10 and 12 and their axis labels
_MU = (("mu1", r"$\mu_1$ [m]"), ("mu2", r"$\mu_2$ literal [m]"), ("mu2_vc", r"$\mu_{2,vc}$ [m]"))
#: adaptive parameters of Figs. 7 and 11 (those a law has) and their axis labels
_ADAPTIVE = (("m_hat", r"$\hat m_i$ [kg]"), ("beta_hat", r"$\hat\beta_i$ [-]"))
_ADAPTIVE += (("d_hat", r"$\hat d_i$ [N]"), ("b_hat", r"$\hat b_i$ [N]"))
#: the law of a scenario -> its name in the figures' titles
_LAWS = {"thm1": "Thm 1, eqs. (23)-(27)", "thm2": "Thm 2, eqs. (41)-(45)", "sir-ftc": "SIR-FTC"}


def _label(sc) -> str:
    return f"spacecraft {int(sc)}"


def _zoom_and_full(row, t, y, ylabel: str, *fmt: str, log: bool = False, **style) -> None:
    """One time history on a row of two panels labelled ``ylabel``: its first ZOOM s (left) and the
    whole horizon (right; ``log``: on a log scale, floored at 1e-12)."""
    zoom = t <= ZOOM
    row[0].plot(t[zoom], y[zoom], *fmt, **style)
    if log:
        row[1].semilogy(t, np.maximum(y, 1e-12), *fmt, **style)
    else:
        row[1].plot(t, y, *fmt, **style)
    for ax in row:
        ax.set_ylabel(ylabel)


def plot_errors(ds, path: Path, variable: str, title: str, unit: str) -> Path:
    """Components of e_i1 or e_i2 (rows x, y, z; columns zoom / full horizon)."""
    fig, axes = new_figure(3, 2, width=10.0, sharex=False, title=title)
    sym = "e_{i1}" if variable == "position_error" else "e_{i2}"
    for r, ax_name in enumerate(["x", "y", "z"]):
        for sc in ds.spacecraft.values:
            y = ds[variable].sel(spacecraft=sc, axis=ax_name).values
            lab = f"${sym},{ax_name}$ [{unit}]"
            _zoom_and_full(axes[r], ds.time.values, y, lab, label=_label(sc))
        axes[r, 1].set_yscale("symlog", linthresh=1e-2 if unit == "m" else 1e-3)
    return finish_figure(fig, axes, path, loc="best", ncol=2)


def plot_mu(ds, path: Path, title: str) -> Path:
    """mu1, mu2 (literal, E000-08) and mu2_vc (virtual centre)."""
    fig, axes = new_figure(3, 2, width=10.0, sharex=False, title=title)
    for r, (name, lab) in enumerate(_MU):
        _zoom_and_full(
            axes[r], ds.time.values, ds[name].values, lab, color="k", label=name, log=True
        )
    return finish_figure(fig, axes, path)


def plot_adaptive(ds, path: Path, title: str) -> Path:
    """m_hat, beta_hat, d_hat (Thm 1/2) or b_hat (SIR-FTC) per spacecraft."""
    names = [(n, u) for n, u in _ADAPTIVE if n in ds]
    fig, axes = new_figure(len(names), 2, width=10.0, sharex=False, title=title)
    for r, (name, lab) in enumerate(names):
        for sc in ds.spacecraft.values:
            y = ds[name].sel(spacecraft=sc).values
            _zoom_and_full(axes[r], ds.time.values, y, lab, label=_label(sc))
    return finish_figure(fig, axes, path, loc="best", ncol=2)


def plot_comparison(datasets: dict[str, object], path: Path, title: str) -> Path:
    """Fig. 12: mu1 and mu2 of several runs on a log scale (full horizon and zoom)."""
    fig, axes = new_figure(3, 2, width=10.0, sharex=False, title=title)
    styles = ["-", "--", ":", "-."]
    for k, (label, ds) in enumerate(datasets.items()):
        for r, (name, lab) in enumerate(_MU):
            y = ds[name].values
            _zoom_and_full(axes[r], ds.time.values, y, lab, styles[k % 4], label=label, log=True)
    return finish_figure(fig, axes, path, loc="best")


def plot_scenario(ds, scenario, out_dir) -> list[Path]:
    """Figures of one run of a ``[scenario] paper = "li2020"`` scenario (position/velocity errors,
    mu1/mu2, adaptive parameters).

    Parameters
    ----------
    ds : xarray.Dataset
        The run's records (``position_error``, ``velocity_error``, ``mu1``, ``mu2``, ``mu2_vc`` and the
        law's adaptive parameters).
    scenario : ComposedScenario
        The scenario (its name and its law label the figures).
    out_dir : path-like
        Directory of the PNG files.

    Returns
    -------
    list of Path
        The four figures.
    """
    from formation_ftc.papers.li2020.conditions import law_of

    out_dir = Path(out_dir)
    name = scenario.scenario.name
    ctrl = _LAWS.get(str(law_of(scenario)), str(scenario.type_of("controller")))
    return [
        *(
            plot_errors(ds, out_dir / f"{name}_{v}.png", v, f"{name}: {what} ({ctrl})", unit)
            for v, what, unit in (
                ("position_error", "position tracking errors", "m"),
                ("velocity_error", "velocity tracking errors", "m/s"),
            )
        ),
        plot_mu(
            ds, out_dir / f"{name}_mu.png", f"{name}: formation tracking / keeping errors ({ctrl})"
        ),
        plot_adaptive(
            ds, out_dir / f"{name}_adaptive.png", f"{name}: adaptive parameters ({ctrl})"
        ),
    ]


def trajectories_3d(ds, path: Path) -> Path:
    """Interactive 3-D view of the LVLH trajectories of ``ds``: ``trajectory3d.json`` (the file the
    report page reads) in the directory of ``path``, replaced."""
    from formation_ftc.report.html import write_trajectory3d

    positions = {
        f"spacecraft {int(sc)}": ds.position.sel(spacecraft=sc).values
        for sc in ds.spacecraft.values
    }
    title = "Li2020 Thm 2: LVLH trajectories (x radial, y along-track, z normal)"
    return write_trajectory3d(path.parent, positions, title=title, append=False)
