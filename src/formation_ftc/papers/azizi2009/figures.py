"""Figures of the Azizi & Khorasani 2009 reproduction (numbered like the paper) and of single runs.

* Fig. 2 -- x-axis cumulative input effort E_xi(t) = int u_xi^2 dt, (a) fault-free, (b) LLFR
  alpha_2 = 1, (c) FLFR alpha_2 = 6, (d) FLFR alpha_2 = 10 (caption "HLFR" -> FLFR, E004-06);
* Fig. 3 -- alpha_2 versus (a) ||D|| and (b) the maximum tracking error (simulated sweep);
* Fig. 4 -- analytic alpha_2 of eq. (11) for pi = 0 ... 0.4 and the simulated alpha_2 versus e_s.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from formation_ftc.plotting import SPACECRAFT_COLORS, new_figure, save_figure

# the axes cycle through SPACECRAFT_COLORS: the j-th line of an axes is spacecraft j's colour

__all__ = ["plot_fig2", "plot_fig3", "plot_fig4", "plot_run"]


def plot_fig2(
    efforts: Sequence[tuple[str, np.ndarray, np.ndarray]], path: Path, t_max: float = 100.0
) -> Path:
    """``efforts``: four (title, time [s], E (T, N)) tuples; plotted up to ``t_max`` [s]."""
    title = "Fig. 2: x-axis cumulative input effort E_xi(t)"
    fig, axes = new_figure(2, 2, width=8.0, height=5.6, sharex=False, title=title)
    for ax, (title, t, E) in zip(axes.flat, efforts, strict=True):
        sel = t <= t_max + 1e-9
        for j in range(E.shape[1]):
            ax.plot(t[sel], E[sel, j], label=f"satellite {j + 1}")
        ax.set(title=title, xlabel="time t [s]", ylabel="E_xi [m^2 s^-3]")
        ax.legend(loc="upper left")
    return save_figure(fig, path)


def plot_fig3(
    alpha2: np.ndarray,
    d_norm: np.ndarray,
    max_err: np.ndarray,
    e_s: float,
    alpha_min: float | None,
    path: Path,
) -> Path:
    """alpha_2 versus ||D||_2 (a) and versus the simulated max |e_ij| (b)."""
    title = "Fig. 3: FLFR weight alpha_2 (satellite 2 faulty, LLFR b_hat_2 = 0.88)"
    fig, axes = new_figure(1, 2, width=8.0, height=3.4, sharex=False, title=title)
    ax = axes[0, 0]
    ax.plot(d_norm, alpha2, color=SPACECRAFT_COLORS[1], label="formation (satellite 2 weighted)")
    ax.set(xlabel="||D||_2 [-]", ylabel="alpha_2 [-]", title="(a) alpha_2 vs ||D||")
    ax.legend()
    ax = axes[0, 1]
    ax.plot(max_err, alpha2, color=SPACECRAFT_COLORS[0], label="simulated max |e_ij| (formation)")
    ax.axvline(e_s, color="k", ls="--", lw=0.8, label=f"e_s = {e_s} m")
    if alpha_min is not None:
        ax.axhline(alpha_min, color="0.4", ls=":", lw=0.8, label=f"min alpha_2 = {alpha_min:.1f}")
    ax.set(xlabel="max tracking error [m]", ylabel="alpha_2 [-]")
    ax.set_title("(b) alpha_2 vs max tracking error")
    ax.legend()
    return save_figure(fig, path)


def plot_fig4(
    e_s_grid: np.ndarray,
    analytic: Mapping[float, np.ndarray],
    sim_err: np.ndarray,
    sim_alpha: np.ndarray,
    e_s: float,
    path: Path,
) -> Path:
    """Analytic alpha_2(e_s) of eq. (11) for each pi, and the simulated alpha_2 vs max error."""
    fig, axes = new_figure(
        1, 1, width=6.4, height=4.2, title="Fig. 4: analytic and simulated alpha_2 vs e_s"
    )
    ax = axes[0, 0]
    cmap = __import__("matplotlib").colormaps["viridis"]
    pis = sorted(analytic)
    for j, p in enumerate(pis):
        color = cmap(j / max(1, len(pis) - 1))
        ax.plot(
            e_s_grid, analytic[p], color=color, lw=1.0, label=f"analytic eq. (11), pi = {p:.2f}"
        )
    ax.plot(sim_err, sim_alpha, "k-", lw=2.0, label="simulation (4 satellites)")
    ax.axvline(e_s, color="0.5", ls="--", lw=0.8, label=f"e_s = {e_s} m")
    ax.set(xlabel="error specification e_s / max tracking error [m]", ylabel="alpha_2 [-]")
    ax.set_ylim(0, 12)
    ax.legend(fontsize=6, ncol=2)
    return save_figure(fig, path)


def plot_run(ds, scenario, out_dir: Path) -> list[Path]:
    """Figure of one run of a composed scenario of the paper (``formation-ftc run --plot``): x-axis
    tracking errors per pair with the supervisor's e_s [m], its mode, and the x efforts."""
    t = ds["time"].values
    e_s = scenario.section("supervisor").e_s
    fig, axes = new_figure(3, 1, width=7.0, height=7.0, title=f"{scenario.scenario.name}: x axis")
    ax = axes[0, 0]
    for pair in ds["pair"].values:
        e = ds["tracking_error"].sel(axis="x", pair=pair).values
        ax.plot(t, e, label=f"e_{pair.replace('-', '')}")
    ax.axhline(e_s, color="k", ls="--", lw=0.8, label="+/- e_s")
    ax.axhline(-e_s, color="k", ls="--", lw=0.8)
    ax.set_ylabel("tracking error [m]")
    ax.legend(ncol=4, loc="lower right", fontsize=7)
    ax = axes[1, 0]
    ax.step(t, ds["mode"].values, where="post", color="k", label="HL supervisor mode")
    ax.set_yticks([0, 1, 2], ["Nominal", "LLFR", "FLFR"])
    ax.set_ylabel("mode")
    ax.legend()
    ax = axes[2, 0]
    for scn in ds["spacecraft"].values:
        ax.plot(t, ds["effort"].sel(axis="x", spacecraft=scn).values, label=f"satellite {scn}")
    ax.set(ylabel="E_xi [m^2 s^-3]", xlabel="time t [s]")
    ax.legend(ncol=4)
    return [save_figure(fig, Path(out_dir) / f"{scenario.scenario.name}.png")]
