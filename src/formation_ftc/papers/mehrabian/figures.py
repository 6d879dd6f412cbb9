"""Figures of Mehrabian et al.: Fig. 2 (fault vs FDI estimate) and Figs. 3-5 (attitudes of the eight
spacecraft per case; spacecraft 1 dash-dotted, as in the paper). Angles are plotted in degrees."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from formation_ftc.components.evaluations.mehrabian_metrics import metric_windows
from formation_ftc.plotting import new_figure, save_figure
from formation_ftc.report.run_page import finish_figure

__all__ = ["plot_attitudes", "plot_fault_estimate", "plot_seed_spread", "plot_scenario"]

_LABELS = (r"pitch $\theta$ [deg]", r"roll $\phi$ [deg]", r"yaw $\psi$ [deg]")


def plot_attitudes(ds, path: Path, title: str, window: tuple[float, float] | None = None) -> Path:
    """Three panels (theta, phi, psi) of every spacecraft versus time."""
    fig, axes = new_figure(3, 1, width=7.0, height=7.5, title=title)
    t = ds.time.values
    q = np.rad2deg(ds.attitude.values)
    for p in range(3):
        ax = axes[p, 0]
        for j, sc in enumerate(ds.spacecraft.values):  # colours: the axes' spacecraft cycle
            first = j == 0
            style = dict(linestyle="-." if first else "-", linewidth=1.6 if first else 1.0)
            ax.plot(t, q[:, j, p], **style, label=f"spacecraft {int(sc)}")
        if window is not None:
            ax.axvspan(*window, color="0.9", zorder=0)
        ax.set_ylabel(_LABELS[p])
    return finish_figure(fig, axes, path, loc="upper right", ncol=4, fontsize=7)


def plot_fault_estimate(
    ds, path: Path, spacecraft: int = 1, channel: int = 3, title: str = ""
) -> Path:
    """True additive fault u_bar and the FDI estimate u* in one channel (paper Fig. 2)."""
    fig, axes = new_figure(1, 1, width=6.4, height=3.2, title=title or None)
    ax = axes[0, 0]
    t = ds.time.values
    sub = f"{spacecraft},{channel}"  # the subscript
    for variable, style, color, label in (
        ("fault", "-", "#1f77b4", rf"fault $\bar u_{{{sub}}}$ (spacecraft {spacecraft})"),
        ("fdi_estimate", "--", "#2ca02c", rf"FDI estimate $\bar u^*_{{{sub}}}$"),
        ("fault_estimate_adaptive", ":", "#d62728", rf"adaptive estimate $\hat u_{{{sub}}}$ (19)"),
    ):
        ax.plot(
            t, ds[variable].values[:, spacecraft - 1, channel - 1], style, color=color, label=label
        )
    ax.set(xlabel="time [s]", ylabel="generalised force [N m]")
    ax.legend(loc="best")
    return save_figure(fig, path)


def plot_seed_spread(values: dict[str, np.ndarray], path: Path, ylabel: str, title: str) -> Path:
    """Per-case distribution over seeds (box plot with the individual seeds)."""
    fig, axes = new_figure(1, 1, width=6.4, height=3.4, title=title)
    ax = axes[0, 0]
    names = list(values)
    data = [np.asarray(values[n]) for n in names]
    ax.boxplot(data)
    ax.set_xticks(range(1, len(names) + 1), names)
    for k, d in enumerate(data):
        x = np.full(d.shape, k + 1.0) + np.linspace(-0.12, 0.12, d.size)  # the seeds side by side
        ax.plot(x, d, ".", color="0.3", markersize=4)
    ax.set_ylabel(ylabel)
    return save_figure(fig, path)


def plot_scenario(ds, scenario, out_dir: Path) -> list[Path]:
    """Figures of one run of a composed scenario with ``[scenario] paper = "mehrabian"``: attitudes
    (grey: the fault window of its ``mehrabian-metrics`` evaluation), and the fault vs the FDI and
    adaptive estimates of the actuator's first fault.

    Parameters
    ----------
    ds : xarray.Dataset
        The run's records (Euler angles ``attitude`` [rad], faults and estimates [N m]).
    scenario : ComposedScenario
        The scenario that was run.
    out_dir : Path
        Folder of the PNG files.

    Returns
    -------
    list of Path
        The files written.
    """
    out_dir = Path(out_dir)
    name = scenario.scenario.name
    windows = metric_windows(scenario)
    window = None if windows is None else windows["fault_window"]
    paths = []
    if "attitude" in ds:
        paths.append(plot_attitudes(ds, out_dir / "attitudes.png", f"{name}: Euler angles", window))
    faults = getattr(scenario.section("actuator"), "faults", None)
    if faults and all(v in ds for v in ("fault", "fdi_estimate", "fault_estimate_adaptive")):
        f, title = faults[0], f"{name}: fault and estimates"
        path = out_dir / "fault_estimate.png"
        paths.append(plot_fault_estimate(ds, path, f.spacecraft, f.channel, title))
    return paths
