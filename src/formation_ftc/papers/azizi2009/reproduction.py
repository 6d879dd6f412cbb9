"""Reproduction ``azizi2009``: scenarios (a)-(c), the alpha_2 sweep, the analytic FLFR design, the
seed spread, figures 2-4 and the paper-vs-ours table (errata E004-* in docs/errata.md).

Steps (all runs fixed-seed; noise off except in the seed spread, E004-09):

1. offline design (:func:`formation_ftc.design.flfr.design_flfr`): q1, q2, cofactors, H_i from A_clp
   at alpha_2 = 1 (and from the nominal A), alpha_2(pi) of eq. (11) on pi = 0, 0.05, ..., 0.40,
   small-gain margin gamma_1, disturbance floor T_i;
2. single runs: (a) fault-free, (b) LLFR alpha_2 = 1, (c) FLFR alpha_2 = 6 and 10 (Fig. 2), the HL
   supervisor run (LLFR -> FLFR with the analytic alpha_2) and a run with the analytic alpha_2 from t = 0;
3. alpha_2 sweep 1.0 ... 10.0 on a 0.1 grid (x axis only; y and z are unaffected by the x fault) as one
   ``jax.vmap`` batch; smallest grid alpha_2 with max |e_ij| <= e_s;
4. seed spread: 20 seeds with noise sigma = 1e-5 m on e_ij and 1e-5 m/s on de_ij/dt (E004-09), alpha_2 = 1
   plus a +/- 0.5 window of the 0.1 grid around the noise-free minimum, one vmapped batch; a seed whose
   minimum falls on the window edge is flagged in the notes.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from formation_ftc.api import load_scenario
from formation_ftc.components.controllers.azizi2009_llfr import flfr_design
from formation_ftc.methods.composed import ComposedScenario, make_loop
from formation_ftc.papers.azizi2009.conditions import conditions, d_norms
from formation_ftc.papers.azizi2009.figures import plot_fig2, plot_fig3, plot_fig4
from formation_ftc.papers.azizi2009.published import CITATION, PUBLISHED, TITLE
from formation_ftc.papers.programs import simulate
from formation_ftc.registry import ComparisonRow, Figure, PaperReport, Reproduction
from formation_ftc.report.profile import phase
from formation_ftc.sim.batch import batched_grid_run, batched_run, stack_params, stack_params_grid
from formation_ftc.sim.compiled import compile_loop
from formation_ftc.sim.loop import ClosedLoop
from formation_ftc.sim.metrics import metrics_dict

__all__ = [
    "run_reproduction",
    "run_batch",
    "VARIABLE",
    "REPRODUCTION",
    "PUBLISHED",
    "alpha_min_on_grid",
]

PI_GRID = tuple(round(0.05 * j, 2) for j in range(9))
SEEDS = 20
NOISE_SIGMA = 1e-5


def alpha_min_on_grid(alpha: np.ndarray, max_err: np.ndarray, e_s: float) -> float | None:
    """Smallest grid alpha whose max error is <= e_s (None if none); ``alpha`` ascending."""
    ok = np.nonzero(np.asarray(max_err) <= e_s)[0]
    return float(alpha[ok[0]]) if ok.size else None


def _interp_alpha(alpha: np.ndarray, max_err: np.ndarray, e_s: float) -> float:
    """alpha at which the (decreasing) simulated max error crosses e_s (linear interpolation)."""
    me = np.asarray(max_err)
    return float(np.interp(e_s, me[::-1], np.asarray(alpha)[::-1]))


def _rel(ours: float, pub: float) -> float:
    return abs(ours - pub) / abs(pub)


#: what :func:`run_batch` may vary: name -> (component, field) of the closed loop (None: the loop)
VARIABLE = {
    "alpha": ("controller", "alpha"),
    "alpha_flfr": ("controller", "alpha_flfr"),
    "seed": (None, "seed"),
}


def _variant(loop: ClosedLoop, values: Mapping[str, Any]) -> ClosedLoop:
    for name, value in values.items():
        slot, field = VARIABLE[name]
        old = getattr(loop, field) if slot is None else getattr(getattr(loop, slot), field)
        new = jnp.asarray(value, dtype=jnp.result_type(old))
        change: dict[str, Any] = {field: new}
        if slot is None:
            loop = dataclasses.replace(loop, **change)
        else:
            loop = dataclasses.replace(
                loop, **{slot: dataclasses.replace(getattr(loop, slot), **change)}
            )
    return loop


def run_batch(
    sc: ComposedScenario,
    variations: Mapping[str, np.ndarray],
    grid: tuple[int, int] | None = None,
) -> list[dict[str, float]]:
    """Metrics of len(batch) runs of ``sc`` (a scenario of the paper's law on the double-integrator
    plant) that differ only in the given leaves (see :data:`VARIABLE`: ``alpha`` (B, N),
    ``alpha_flfr`` (B,), ``seed`` (B,)), run as one compiled, vmapped program through
    :mod:`formation_ftc.sim.batch` (leaves shared by every run stay unbatched). Each run's metrics also
    carry ``D_norm_llfr`` / ``D_norm_flfr``: ||D||_2 of eq. (6) from its weights (true eps).

    ``grid = (rows, columns)``: run b is cell ``(b // columns, b % columns)`` of a grid (B = rows x
    columns), batched by two nested maps (:func:`formation_ftc.sim.batch.stack_params_grid`): a leaf
    that changes only from row to row -- a seed per row -- is batched once per row, and so is the work
    that depends on it alone (the noise draws). Same metrics, in the same order.
    Raises ``RuntimeError`` naming a run that diverged."""
    unknown = set(variations) - set(VARIABLE)
    if unknown:
        raise KeyError(f"unknown variations {sorted(unknown)}; valid: {sorted(VARIABLE)}")
    sizes = {np.asarray(v).shape[0] for v in variations.values()}
    if len(sizes) != 1:
        raise ValueError(f"all variations need the same batch size, got {sizes}")
    (size,) = sizes
    loop = make_loop(sc)
    compiled = compile_loop(loop)
    loops = [
        _variant(loop, {k: np.asarray(v)[b] for k, v in variations.items()}) for b in range(size)
    ]
    if grid is None:
        batch, axes = stack_params(loops)
        out = jax.device_get(batched_run(compiled, axes, size)(batch))
    else:
        rows, cols = (int(g) for g in grid)
        if rows < 1 or cols < 1 or rows * cols != size:
            raise ValueError(f"grid = {grid}: rows x columns must equal the batch size {size}")
        batch, row_axes, col_axes = stack_params_grid(
            [loops[r * cols : (r + 1) * cols] for r in range(rows)]
        )
        out = jax.device_get(batched_grid_run(compiled, row_axes, col_axes, rows, cols)(batch))
        out = jax.tree_util.tree_map(lambda a: np.reshape(a, (size,) + np.shape(a)[2:]), out)
    res = []
    for b, lp in enumerate(loops):
        div = int(out["diverged_step"][b])
        if div >= 0:
            raise RuntimeError(f"batch member {b} diverged at step {div}")
        m = metrics_dict(loop.metrics, [np.asarray(v)[b] for v in out["metrics"]])
        ctl = lp.controller
        m["D_norm_llfr"], m["D_norm_flfr"] = d_norms(
            sc, lp, np.asarray(ctl.alpha), float(np.asarray(ctl.alpha_flfr))
        )
        res.append(m)
    return res


def run_reproduction(
    out_dir: Path,
    progress: Callable[[float, str], None] = lambda f, m: None,
    horizon: float = 300.0,
    sweep_step: float = 0.1,
    seeds: int = SEEDS,
    seed_window: float = 0.5,
) -> PaperReport:
    """Run the study (see module docstring); ``horizon``/``sweep_step``/``seeds`` reduce it for tests."""
    t_start = time.time()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    hz = {"simulation.horizon": horizon}
    e_s = 0.03

    progress(0.02, "FLFR design (H_i, eq. (11))")
    sc_llfr = load_scenario("azizi2009-llfr", hz)
    law = sc_llfr.section("controller")
    design = flfr_design(law, sc_llfr.section("plant").count, e_s, PI_GRID)
    a_an = design.alpha
    a_an0 = float(a_an[0.0])

    progress(0.08, "scenarios (a), (b), supervisor")
    x_only = {**hz, "plant.axes": 1}
    sc_sv = load_scenario("azizi2009-flfr", hz)
    with phase("run"):
        ds_ff, m_ff = simulate(load_scenario("azizi2009-fault-free", hz))
        ds_ll, m_ll = simulate(sc_llfr)
        _, m_sv = simulate(sc_sv)
        ds_6, m_6 = simulate(
            load_scenario("azizi2009-llfr", {**x_only, "controller.alpha": [1.0, 6.0, 1.0, 1.0]})
        )
        ds_10, m_10 = simulate(
            load_scenario("azizi2009-llfr", {**x_only, "controller.alpha": [1.0, 10.0, 1.0, 1.0]})
        )
        _, m_an = simulate(
            load_scenario("azizi2009-llfr", {**x_only, "controller.alpha": [1.0, a_an0, 1.0, 1.0]})
        )

    progress(0.25, "alpha_2 sweep (one vmapped batch)")
    n_grid = round(9.0 / sweep_step) + 1
    alpha_grid = np.round(1.0 + sweep_step * np.arange(n_grid), 10)
    sc_sweep = load_scenario("azizi2009-llfr", {**x_only, "simulation.record_every": 1000})
    A = np.ones((n_grid, 4))
    A[:, 1] = alpha_grid
    with phase("run"):
        res = run_batch(sc_sweep, {"alpha": A})
    max_err = np.array([r["max_err"] for r in res])
    d_norm = np.array([r["D_norm_llfr"] for r in res])
    a_min = alpha_min_on_grid(alpha_grid, max_err, e_s)
    a_interp = _interp_alpha(alpha_grid, max_err, e_s)

    progress(0.6, f"seed spread ({seeds} seeds, noise on)")
    center = a_min if a_min is not None else 10.0
    half = round(seed_window / sweep_step)
    win = np.round(center + sweep_step * np.arange(-half, half + 1), 10)
    win = win[(win >= 1.0 - 1e-9) & (win <= 10.0 + 1e-9)]
    per_seed = np.concatenate([[1.0], win])
    sc_noise = load_scenario(
        "azizi2009-llfr",
        {
            **x_only,
            "simulation.record_every": 1000,
            "sensors.position_noise_std": NOISE_SIGMA,
            "sensors.velocity_noise_std": NOISE_SIGMA,
        },
    )
    seed_ids = np.arange(seeds)
    SA = np.ones((seeds * per_seed.size, 4))
    SA[:, 1] = np.tile(per_seed, seeds)
    SS = np.repeat(seed_ids, per_seed.size)
    with phase("run"):
        # a grid, seeds x weights: each seed's noise is drawn once for its row of weights
        res_s = run_batch(sc_noise, {"alpha": SA, "seed": SS}, grid=(seeds, per_seed.size))
    me_s = np.array([r["max_err"] for r in res_s]).reshape(seeds, per_seed.size)
    llfr_seed = me_s[:, 0]
    amin_seed = []
    edge = []
    for j in range(seeds):
        a = alpha_min_on_grid(win, me_s[j, 1:], e_s)
        if a is None or a <= win[0] + 1e-9:
            edge.append(j)
        amin_seed.append(np.nan if a is None else a)
    amin_seed = np.asarray(amin_seed)
    any_seed = bool(np.any(np.isfinite(amin_seed)))  # a seed met e_s inside the window

    progress(0.85, "figures")
    eff = [
        (title, ds["time"].values, ds["effort"].sel(axis="x").values)
        for title, ds in (
            ("(a) fault-free", ds_ff),
            ("(b) LLFR, alpha_2 = 1", ds_ll),
            ("(c) FLFR, alpha_2 = 6", ds_6),
            ("(d) FLFR, alpha_2 = 10", ds_10),
        )
    ]
    with phase("plot"):
        plot_fig2(eff, out_dir / "fig2_effort.png")
        plot_fig3(alpha_grid, d_norm, max_err, e_s, a_min, out_dir / "fig3_alpha2.png")
    es_grid = np.linspace(0.012, 0.07, 200)
    coeff = design.coefficients
    analytic_curves = {
        p: np.array(
            [law.b_eps * (1 - p) * design.H / (coeff.q2 * e) - coeff.q1 / coeff.q2 for e in es_grid]
        )
        for p in PI_GRID
    }
    with phase("plot"):
        plot_fig4(
            es_grid, analytic_curves, max_err, alpha_grid, out_dir / "fig4_analytic_vs_sim.png", e_s
        )
    figs = [
        Figure(
            "fig2_effort.png",
            "2",
            "x-axis cumulative input effort: (a) fault-free, (b) LLFR "
            "alpha_2 = 1, (c) FLFR alpha_2 = 6, (d) FLFR alpha_2 = 10 (E004-06: caption HLFR -> FLFR)",
        ),
        Figure(
            "fig3_alpha2.png",
            "3",
            "alpha_2 versus (a) ||D||_2 and (b) simulated max tracking error",
        ),
        Figure(
            "fig4_analytic_vs_sim.png",
            "4",
            "analytic alpha_2 (eq. (11), pi = 0..0.4, H from A_clp "
            "at alpha_2 = 1) and simulated alpha_2 versus e_s",
        ),
    ]

    # ---------------------------------------------------------------- summary
    t_cmp = min(100.0, horizon)

    def e_at(ds) -> list[float]:
        return [
            float(v) for v in ds["effort"].sel(axis="x").sel(time=t_cmp, method="nearest").values
        ]

    E = {
        "fault_free": e_at(ds_ff),
        "alpha2_1": e_at(ds_ll),
        "alpha2_6": e_at(ds_6),
        "alpha2_10": e_at(ds_10),
    }
    summary = {
        "max_err_fault_free": m_ff["max_err"],
        "max_err_llfr": m_ll["max_err"],
        "alpha2_min_simulated": a_min,
        "alpha2_min_simulated_interpolated": a_interp,
        "alpha2_analytic_pi_0": a_an0,
        "alpha2_analytic_pi_0.15": float(a_an[0.15]),
        "alpha2_analytic_pi_0.2": float(a_an[0.2]),
        "alpha2_analytic_pi_0.4": float(a_an[0.4]),
        "alpha2_analytic_nominal_A": {
            f"pi_{p:g}": float(v) for p, v in design.alpha_nominal_H.items()
        },
        "alpha2_analytic_all_pi": {f"pi_{p:g}": float(v) for p, v in a_an.items()},
        "H1_clp_alpha2_1": design.H,
        "H1_nominal_A": design.H_nominal,
        "q1": coeff.q1,
        "q2": coeff.q2,
        "DET_alpha2_1": coeff.det(1.0),
        "cofactors_C_k2": coeff.f.tolist(),
        "gamma1": design.small_gain.gamma1,
        "B_Delta": design.small_gain.b_delta,
        "Delta_norm_alpha2_1": design.delta_norm_reference,
        "bound8_alpha2_1": design.bound_at_reference,
        "disturbance_floor_T": design.floor,
        "max_err_analytic_alpha2_pi_0": m_an["max_err"],
        "supervisor_t_flfr": m_sv["t_flfr"],
        "supervisor_alpha2": float(np.asarray(make_loop(sc_sv).controller.alpha_flfr)),
        "supervisor_max_err_after_settle": m_sv["max_err_after_flfr"],
        "supervisor_max_err": m_sv["max_err"],
        f"effort_x_at_{t_cmp:g}s": E,
        "seed_spread": {
            "seeds": int(seeds),
            "noise_sigma_position_m": NOISE_SIGMA,
            "noise_sigma_velocity_m_s": NOISE_SIGMA,
            "alpha2_min_simulated_min": float(np.nanmin(amin_seed)) if any_seed else None,
            "alpha2_min_simulated_max": float(np.nanmax(amin_seed)) if any_seed else None,
            "alpha2_min_simulated_mean": float(np.nanmean(amin_seed)) if any_seed else None,
            "max_err_llfr_min": float(llfr_seed.min()),
            "max_err_llfr_max": float(llfr_seed.max()),
            "max_err_llfr_std": float(llfr_seed.std()),
            "seeds_at_window_edge": edge,
        },
    }

    # ---------------------------------------------------------------- comparison rows
    why = (
        "E004-08: nominal b_i, sign of eps, fault onset, labelling and H_i computation are unstated; "
        "our baseline b = 1, b_hat_2 = 0.88"
    )
    nan = float("nan")
    a_min_v = float(a_min) if a_min is not None else nan
    rows: list[ComparisonRow] = [
        ComparisonRow.judged(
            "(a) fault-free max |e_ij| [m]",
            "about 1e-4 m (Sec. V, case (a))",
            f"{m_ff['max_err']:.2g}",
            "same order: <= 2e-4 m",
            (("<=", m_ff["max_err"], 2e-4),),
            "dt = 1e-3 ZOH discretisation error, noise off (E004-09)",
        ),
        ComparisonRow.judged(
            "(b) LLFR-only max |e_ij| [m], alpha_2 = 1",
            "0.072 m (Sec. V, case (b))",
            f"{m_ll['max_err']:.4f}",
            "within 10 %",
            (("rel<=", m_ll["max_err"], 0.072, 0.10),),
            why + f" ({100 * _rel(m_ll['max_err'], 0.072):.0f} % off)",
        ),
        ComparisonRow.judged(
            "simulated min alpha_2 for e_s = 0.03 m (0.1 grid)",
            "5.6 (Sec. V, case (c); Fig. 4)",
            f"{a_min} (interpolated {a_interp:.2f})",
            "within 0.3",
            (("abs<=", a_min_v, 5.6, 0.3),),
            why,
        ),
    ]
    for p in (0.0, 0.15, 0.2, 0.4):
        pub = PUBLISHED["alpha2_analytic"][p]
        ours = float(a_an[p])
        rows.append(
            ComparisonRow.judged(
                f"analytic alpha_2, eq. (11), pi = {p:g}",
                f"{pub} (Sec. V, case (c); Fig. 4)",
                f"{ours:.2f} (nominal-A H: {design.alpha_nominal_H[p]:.2f})",
                "within 10 %",
                (("rel<=", ours, pub, 0.10),),
                why + "; the paper's four values are only approximately linear in 1 - pi "
                "(their line predicts 5.5 at pi = 0.2) and imply q1/q2 ~ 2.9, b_hat_2 ~ 0.98",
            )
        )
    # theory relations
    vals = np.array([a_an[p] for p in PI_GRID])
    lin = np.polyfit(1 - np.array(PI_GRID), vals, 1)
    lin_res = float(np.max(np.abs(np.polyval(lin, 1 - np.array(PI_GRID)) - vals)))
    cases = ("alpha2_1", "alpha2_6", "alpha2_10")
    e2 = [E[c][1] for c in cases]
    others = [[E[c][j] for c in cases] for j in (0, 2, 3)]
    sg = design.small_gain
    rows += [
        ComparisonRow.judged(
            "relation: analytic alpha_2 decreases as pi grows",
            "7.6 > 6.0 > 5.4 > 3.4 (Sec. V, case (c))",
            " > ".join(f"{v:.2f}" for v in vals[[0, 3, 4, 8]]),
            "strictly decreasing on pi = 0, 0.05, ..., 0.4",
            (("decreasing", vals),),
            f"linear in 1 - pi: max residual {lin_res:.1e}",
        ),
        ComparisonRow.judged(
            "relation: deterministic alpha_2 (pi = 0) >= simulated minimum (conservative)",
            "7.6 >= 5.6 (Sec. V, case (c); Fig. 4)",
            f"{a_an0:.2f} >= {a_min} (interpolated {a_interp:.2f})",
            "alpha_2(pi=0) >= simulated grid minimum",
            ((">=", a_an0, a_min_v),),
            f"H from A_clp at alpha_2 = 1; with the nominal A it is {design.alpha_nominal_H[0.0]:.2f} "
            "(not conservative)",
        ),
        ComparisonRow.judged(
            "relation: LLFR alone violates e_s",
            "0.072 m > 0.03 m = e_s (Sec. V, case (b))",
            f"{m_ll['max_err']:.4f} > {e_s}",
            "max error > e_s",
            ((">", m_ll["max_err"], e_s),),
        ),
        ComparisonRow.judged(
            "relation: FLFR with the analytic alpha_2 meets e_s",
            "e_s met by FLFR (Sec. V, case (c); Fig. 4)",
            f"{m_an['max_err']:.4f} at alpha_2 = {a_an0:.2f}; supervised run after settling "
            f"{m_sv['max_err_after_flfr']:.4f} (switch at t = {m_sv['t_flfr']:.3f} s)",
            "max error <= e_s (analytic alpha_2 from t = 0, and supervised run after the switch)",
            (("<=", m_an["max_err"], e_s), ("<=", m_sv["max_err_after_flfr"], e_s)),
            "the supervised run exceeds e_s briefly before the switch (it is the trigger)",
        ),
        ComparisonRow.judged(
            "relation: satellite 2 effort falls, others rise as alpha_2 = 1 -> 6 -> 10",
            "Fig. 2 (b)-(d)",
            f"E_x2({t_cmp:g} s) = "
            + " > ".join(f"{v:.1f}" for v in e2)
            + "; E_x1 = "
            + " < ".join(f"{v:.1f}" for v in others[0]),
            "E_x2 strictly decreasing, E_x1, E_x3, E_x4 strictly increasing",
            (("decreasing", e2),) + tuple(("decreasing", [-v for v in o]) for o in others),
        ),
        ComparisonRow.judged(
            "relation: max error decreases with alpha_2 (Theorem 2)",
            "Fig. 3(b) and Sec. V, case (c)",
            f"{max_err[0]:.4f} -> {max_err[-1]:.4f}",
            "strictly decreasing on the grid",
            (("decreasing", max_err),),
        ),
        ComparisonRow.judged(
            "relation: ||D|| decreases with alpha_2 (Lemma 1)",
            "Fig. 3(a) and Sec. V, case (c)",
            f"{d_norm[0]:.4f} -> {d_norm[-1]:.4f}",
            "strictly decreasing",
            (("decreasing", d_norm),),
        ),
        ComparisonRow.judged(
            "Theorem 1 small gain: ||Delta|| < B_Delta at alpha_2 = 1",
            "Theorem 1 (condition only, no numbers)",
            f"||Delta|| = {design.delta_norm_reference:.3f} < B_Delta = {sg.b_delta:.4f} (gamma_1 = {sg.gamma1:.4f})",
            "||Delta|| < B_Delta = 1 / gamma_1 with gamma_1 a certified upper bound",
            (
                ("<", design.delta_norm_reference, sg.b_delta),
                ("true", sg.norm is None or sg.norm.certified),
            ),
            "E004-05: gamma_1 = sqrt(2); nominal system stable even without FLFR. "
            + sg.certificate,
        ),
        ComparisonRow.judged(
            "bound (8) at alpha_2 = 1 vs simulated max error",
            "eq. (8) (bound only, no numbers)",
            f"{design.bound_at_reference:.4f} vs {m_ll['max_err']:.4f}",
            "bound >= simulation (within 1 %)",
            ((">=", design.bound_at_reference, 0.99 * m_ll["max_err"]),),
            "nearly tight there because the reduced model (7) is exact",
        ),
    ]
    notes = [
        "H_i by simulating X' = A_clp X + [0,1,0,-1]^T (f . xdd^d) from zero ICs over 300 s, A_clp at alpha_2 = 1 "
        "and eps = +/- B_eps (larger kept); eq. (11) used literally (disturbance floor not subtracted; "
        f"T = {design.floor:.2e} m).",
        "Sweep and seed spread simulate the x axis only (y, z are decoupled and fault-free).",
        f"Seed spread: {seeds} seeds, noise sigma = {NOISE_SIGMA} on e_ij and de_ij/dt (the paper's "
        "variance 1e-4 would give ~4e-3 m fault-free error, E004-09).",
    ]
    if edge:
        notes.append(
            f"seeds {edge}: minimum alpha_2 at/below the window edge {win[0]} (window too narrow)"
        )
    progress(1.0, "done")
    return PaperReport(
        paper="azizi2009",
        summary=summary,
        rows=rows,
        figures=figs,
        checks=[],
        scenarios=["azizi2009-fault-free", "azizi2009-llfr", "azizi2009-flfr"],
        seeds=sorted({0, *(int(s) for s in seed_ids)}),
        notes=notes,
        wall_time_s=time.time() - t_start,
    )


def _run(out_dir: Path, progress: Callable[[float, str], None]) -> PaperReport:
    rep = run_reproduction(out_dir, progress)
    sc = load_scenario("azizi2009-flfr")
    rep.checks = conditions(sc, make_loop(sc))
    return rep


REPRODUCTION = Reproduction(
    paper="azizi2009",
    title=TITLE,
    citation=CITATION,
    description="LLFR allocation + HL supervisor + FLFR weight design (eqs. (9), (11)); alpha_2 sweep 1..10, "
    "analytic alpha_2(pi), 20-seed spread",
    errata=[
        ("E004-01", "X = [e12, e12', e23, e23']"),
        ("E004-02", "J_aug last row uses b_hat_2 (implementable Lagrange condition)"),
        ("E004-03", "DET = -det(J_aug) = q2 alpha_2 + q1; cofactors C_k2 free of alpha_2, b_hat_2"),
        ("E004-05", "gamma_1 = sqrt(2), B_Delta = 0.7071"),
        ("E004-06", "'decrease alpha_2' -> increase; Fig. 2 'HLFR' -> FLFR"),
        ("E004-07", "T_i over all omega"),
        ("E004-08", "published numbers not reproducible from the printed data; relations checked"),
        ("E004-09", "noise off by default, dt = 1e-3"),
        ("E004-10", "satellite-dependent disturbance 1e-5 cos(0.01 t + i)"),
    ],
    run=_run,
)
