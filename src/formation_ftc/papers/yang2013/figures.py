"""Figures of Yang2013: Fig. 4 (|X_sigma(t)(t)| with the guaranteed envelope) and Fig. 5 (|u_2(t)|)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from formation_ftc.plotting import SPACECRAFT_COLORS, new_figure, save_figure

__all__ = ["plot_scenario", "figure_4", "figure_5"]


def _semilogy_active(ax, t, ds, variable: str, act) -> None:
    """One semilogy line per spacecraft of ``ds[variable]`` (time, spacecraft), drawn only while the
    spacecraft is in the formation (``act``); spacecraft never active are left out of the legend."""
    for s, sc_id in enumerate(ds["spacecraft"].values):
        if not act[:, s].any():
            continue
        y = np.where(act[:, s], ds[variable].values[:, s], np.nan)
        ax.semilogy(
            t, y, color=SPACECRAFT_COLORS[s % len(SPACECRAFT_COLORS)], label=f"spacecraft {sc_id}"
        )


def _switch_lines(ax, ds) -> None:
    """Dotted lines at the recorded mode changes."""
    mode = np.asarray(ds["mode"].values)
    t = np.asarray(ds["time"].values)
    for ts in t[1:][mode[1:] != mode[:-1]]:
        ax.axvline(float(ts), color="0.6", lw=0.7, ls=":")


def plot_scenario(ds, scenario, out_dir: Path) -> list[Path]:
    """Per-scenario figures: |X| with envelope, |x_i| per spacecraft, |u_i| per spacecraft."""
    from formation_ftc.papers.yang2013.conditions import design_quantities

    out_dir = Path(out_dir)
    q = design_quantities(scenario)
    t = ds["time"].values
    fig, axes = new_figure(3, 1, width=7.0, height=7.5, title=f"{scenario.scenario.name}")
    ax = axes[0, 0]
    ax.plot(t, ds["state_norm"].values, color="k", label="|X_sigma(t)(t)|")
    envelope, pre = q["envelope"], q["pre_switch_bound"]
    ax.axhline(envelope, color="r", ls="--", label=f"eps + (S+2) zeta D = {envelope:.3f}")
    ax.axhline(pre, color="0.4", ls="-.", label=f"eps1 + zeta D = {pre:.2f}")
    _switch_lines(ax, ds)
    ax.set_ylabel("|X| [-]")
    ax.legend(loc="upper right")
    act = ds["active"].values.astype(bool)
    for ax, variable, ylabel in (
        (axes[1, 0], "spacecraft_norm", "|x_i| [-]"),
        (axes[2, 0], "input_norm", "|u_i| [N, N m]"),
    ):
        _semilogy_active(ax, t, ds, variable, act)
        _switch_lines(ax, ds)
        ax.set_ylabel(ylabel)
        ax.legend(loc="upper right", ncol=3)
    ax.set_xlabel("time t [s]")
    return [save_figure(fig, out_dir / f"{scenario.scenario.name}.png")]


def figure_4(ds_healthy, ds_fault, envelope: float, pre_bound: float, path: Path) -> Path:
    """Fig. 4: trajectories of |X_sigma(t)(t)| (healthy and spacecraft-2 controller fault)."""
    title = "Yang2013 Fig. 4: trajectories of |X_sigma(t)(t)|"
    fig, axes = new_figure(2, 1, width=7.0, height=6.0, sharex=True, title=title)
    ax = axes[0, 0]
    ax.plot(ds_healthy["time"], ds_healthy["state_norm"], color="#1f77b4", label="healthy")
    fault = "spacecraft 2 controller fault at 3800 s"
    ax.plot(ds_fault["time"], ds_fault["state_norm"], color="#d62728", ls="--", label=fault)
    ax.axhline(
        envelope, color="k", ls="--", lw=0.9, label=f"envelope eps + (S+2) zeta D = {envelope:.3f}"
    )
    switch_bound = f"switch bound eps1 + zeta D = {pre_bound:.2f}"
    ax.axhline(pre_bound, color="0.5", ls="-.", lw=0.9, label=switch_bound)
    _switch_lines(ax, ds_healthy)
    ax.set_ylabel("|X_sigma(t)(t)| [-]")
    ax.legend(loc="upper right")
    ax = axes[1, 0]
    t = ds_fault["time"].values
    act = ds_fault["active"].values.astype(bool)
    _semilogy_active(ax, t, ds_fault, "spacecraft_norm", act)
    _switch_lines(ax, ds_fault)
    ax.set(ylabel="|x_i| (fault scenario) [-]", xlabel="time t [s]")
    ax.legend(loc="lower left", ncol=3)
    return save_figure(fig, path)


def figure_5(ds_healthy, ds_fault, path: Path, t_end: float = 4000.0) -> Path:
    """Fig. 5: |u_2(t)| on [0, 4000) s until spacecraft 2 departs."""
    fig, axes = new_figure(
        1, 1, width=7.0, height=3.4, title="Yang2013 Fig. 5: trajectories of |u_2(t)|"
    )
    ax = axes[0, 0]
    for ds, color, label in (
        (ds_fault, "#d62728", "spacecraft 2, K2 -> K2f at 3800 s"),
        (ds_healthy, "#1f77b4", "spacecraft 2, healthy"),
    ):
        t = ds["time"].values
        u2, keep = ds["input_norm"].sel(spacecraft=2).values, t < t_end
        ax.semilogy(t[keep], u2[keep], color=color, lw=0.8, label=label)
    ax.axvline(3800.0, color="0.5", lw=0.8, ls=":")
    ax.set(xlabel="time t [s]", ylabel="|u_2| = |[f_2; tau_2]| [N, N m]")
    ax.legend(loc="upper right")
    return save_figure(fig, path)
