"""Figures 3-10 of Gui et al. 2022 from result datasets (matplotlib via formation_ftc.plotting).

Every figure function takes xarray Datasets of the deputy (:func:`deputy` of a result of a
``gui2022-*`` scenario) and returns the written PNG path; :func:`plot` is the figure set of
``formation-ftc run --figures`` (and ``plot``) for a scenario with ``[scenario] paper = "gui2022"``.
The single deputy is called "deputy" in legends; times in s, positions in m, accelerations in m/s^2.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from formation_ftc.plotting import new_figure, save_figure
from formation_ftc.report.run_page import finish_figure

__all__ = [
    "deputy",
    "fig3_fault_reconstruction",
    "fig45_estimation_errors",
    "fig6_ilo_comparison",
    "fig78_tracking_errors",
    "fig9_trajectory",
    "fig10_synthesized_disturbance",
    "plot",
]

AX = ["x", "y", "z"]
#: velocity (True) or position (False) -> the state components and their unit
_COMPONENTS = {False: (AX, "m"), True: (["vx", "vy", "vz"], "m/s")}


def deputy(ds):
    """The single deputy's variables (the ``spacecraft`` dimension of a result dataset removed)."""
    return ds.isel(spacecraft=0) if "spacecraft" in ds.dims else ds


def fig3_fault_reconstruction(ds, path: Path) -> Path:
    """Fig. 3: F_hat vs F per axis (new ILO)."""
    fig, axes = new_figure(3, 1, title="Fig. 3: thruster-fault reconstruction by the ILO (deputy)")
    t = ds.time.values
    for k, a in enumerate(AX):
        ax = axes[k, 0]
        estimate = ds.fault_estimate_mean.sel(axis=a)
        ax.plot(t, ds.fault.sel(axis=a), "k--", label=f"true fault F_{a}")
        ax.plot(t, estimate, label=f"reconstructed F_hat_{a} (record-interval mean)")
        ax.set_ylabel(f"F_{a} [m/s^2]")
    return finish_figure(fig, axes, path, loc="upper left")


def fig45_estimation_errors(ds_offset, ds_full, path: Path, velocity: bool) -> Path:
    """Figs. 4 (position) / 5 (velocity): estimation error q - q_hat; left q_hat(0) offset, right full run."""
    comps, unit = _COMPONENTS[velocity]
    what = "velocity" if velocity else "position"
    num = 5 if velocity else 4
    title = f"Fig. {num}: {what} estimation error of the ILO (deputy)"
    fig, axes = new_figure(1, 2, width=9.0, height=3.4, sharex=False, title=title)
    for ax, ds, ttl in (
        (axes[0, 0], ds_offset, "q_hat(0) = q(0) + offset"),
        (axes[0, 1], ds_full, "q_hat(0) = q(0), faults at 1500 s / 2000 s"),
    ):
        for c in comps:
            ax.plot(ds.time, ds.estimation_error.sel(component=c), label=f"e_{c}")
        ax.set(title=ttl, xlabel="time [s]", ylabel=f"{what} error [{unit}]")
        ax.legend(loc="best")
    return save_figure(fig, path)


def fig6_ilo_comparison(ds_new, ds_base, path: Path) -> Path:
    """Fig. 6: x-axis reconstruction, new ILO vs ILO of ref. [25] (no sign term), and their errors."""
    fig, axes = new_figure(2, 1, title="Fig. 6: new ILO vs ILO of [25] (x axis, deputy)")
    t = ds_new.time.values
    axes[0, 0].plot(t, ds_new.fault.sel(axis="x"), "k--", label="true F_x")
    axes[0, 0].plot(t, ds_new.fault_estimate_mean.sel(axis="x"), label="new ILO (with gamma sgn)")
    base = ds_base.fault_estimate_mean.sel(axis="x")
    axes[0, 0].plot(ds_base.time, base, ":", label="ILO of [25] (gamma = 0)")
    axes[0, 0].set_ylabel("F_x [m/s^2]")
    axes[0, 0].legend(loc="upper left")
    sel = t >= 1400
    e_new = (ds_new.fault - ds_new.fault_estimate_mean).sel(axis="x").values
    e_old = (ds_base.fault - ds_base.fault_estimate_mean).sel(axis="x").values
    axes[1, 0].plot(t[sel], e_new[sel], label="new ILO: F_x - mean F_hat_x")
    axes[1, 0].plot(ds_base.time[sel], e_old[sel], ":", label="ILO of [25]")
    axes[1, 0].plot(
        t[sel], ds_new.disturbance.sel(axis="x")[sel], "k--", lw=0.8, label="perturbation d_x"
    )
    axes[1, 0].set(ylim=(-6e-3, 6e-3), ylabel="error [m/s^2]", xlabel="time [s]")
    axes[1, 0].legend(loc="lower left")
    return save_figure(fig, path)


def fig78_tracking_errors(ds_lof, ds_cof, path: Path, velocity: bool) -> Path:
    """Figs. 7 (position) / 8 (velocity): tracking error e_q = q0 - q, LOF2TC vs COF2TC."""
    what = "velocity" if velocity else "position"
    title = f"Fig. {8 if velocity else 7}: relative {what} tracking error (deputy)"
    curves = ((ds_cof, "COF2TC (u = K e_y)"), (ds_lof, "LOF2TC (30)-(32)"))
    return _tracking_errors(title, curves, velocity, path, loc="upper right")


def _tracking_errors(title: str, curves, velocity: bool, path: Path, **legend) -> Path:
    """Tracking error e_q per component (rows, symlog scale) of each ``(dataset, label)`` of
    ``curves`` (label None: ``e_<component>``); ``legend`` as in :func:`finish_figure`."""
    comps, unit = _COMPONENTS[velocity]
    fig, axes = new_figure(3, 1, title=title)
    for k, c in enumerate(comps):
        for ds, label in curves:
            axes[k, 0].plot(ds.time, ds.tracking_error.sel(component=c), label=label or f"e_{c}")
        axes[k, 0].set_ylabel(f"e_{c} [{unit}]")
        axes[k, 0].set_yscale("symlog", linthresh=1e-4 if velocity else 1e-3)
    return finish_figure(fig, axes, path, **legend)


def fig9_trajectory(ds_lof, ds_cof, path: Path) -> Path:
    """Fig. 9: 3-D relative trajectory vs the nominal 2:1 ellipse."""
    from formation_ftc.plotting import plt

    fig = plt.figure(figsize=(6.4, 5.2))
    ax = fig.add_subplot(111, projection="3d")
    q0 = ds_lof.desired_state.values
    ax.plot(q0[:, 0], q0[:, 1], q0[:, 2], "k--", label="nominal configuration q0 (28)")
    for ds, lab in ((ds_lof, "deputy, LOF2TC"), (ds_cof, "deputy, COF2TC")):
        q = ds.state.values
        ax.plot(q[:, 0], q[:, 1], q[:, 2], label=lab)
    ax.set(xlabel="x [m]", ylabel="y [m]", zlabel="z [m]")
    ax.set_title("Fig. 9: 3-D formation configuration maintenance")
    ax.legend(loc="upper left")
    return save_figure(fig, path)


def fig10_synthesized_disturbance(ds_lof, path: Path) -> Path:
    """Fig. 10: learning term v(t) vs synthesized disturbance h = d + e_F (33)."""
    fig, axes = new_figure(
        3, 1, title="Fig. 10: estimate v of the synthesized disturbance h = d + e_F (deputy)"
    )
    t = ds_lof.time.values
    for k, a in enumerate(AX):
        ax = axes[k, 0]
        h_a = ds_lof.synthesized_disturbance_mean.sel(axis=a)
        ax.plot(t, h_a, "k--", label=f"h_{a} = d_{a} + e_F{a} (record-interval mean)")
        ax.plot(t, ds_lof.compensation.sel(axis=a), label=f"v_{a} (32)")
        h = h_a.values[t > 50]
        lim = 1.5 * np.max(np.abs(h)) if h.size else 1e-2
        ax.set(ylim=(-lim, lim), ylabel=f"h_{a}, v_{a} [m/s^2]")
    return finish_figure(fig, axes, path, loc="upper left")


def plot(ds, scenario, out_dir) -> list[Path]:
    """Figures of one run of a composed ``scenario`` with ``paper = "gui2022"``: the fault
    reconstruction, and the position tracking error when a Gui2022 law runs; returns the PNG paths."""
    out_dir = Path(out_dir)
    ds = deputy(ds)
    paths = [fig3_fault_reconstruction(ds, out_dir / "fault_reconstruction.png")]
    if "tracking_error" in ds:
        title = f"{scenario.scenario.name}: position tracking error (deputy)"
        paths.append(_tracking_errors(title, [(ds, None)], False, out_dir / "tracking_error.png"))
    return paths


def trajectory_3d(ds_lof, ds_cof, path: Path) -> Path:
    """Interactive 3-D view of Fig. 9 (the nominal configuration and both deputies) beside ``path``."""
    from formation_ftc.report.html import write_trajectory3d

    curves = {
        "nominal configuration q0": ds_lof.desired_state.values[:, :3],
        "deputy, LOF2TC": ds_lof.state.values[:, :3],
        "deputy, COF2TC": ds_cof.state.values[:, :3],
    }
    title = "Gui2022 Fig. 9: relative trajectory in LVLH (interactive)"
    return write_trajectory3d(path.parent, curves, title=title, append=False)
