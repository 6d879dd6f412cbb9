"""Azizi2009's alpha_2 study: the batched runs of the law that differ only in the FLFR weights or the
seed (:func:`run_batch`), the alpha_2 sweep on a grid and the noisy seed spread around its minimum
(:func:`alpha2_study`), all as vmapped batches of one compiled program."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any, cast

import jax
import jax.numpy as jnp
import numpy as np

from formation_ftc.api import load_scenario
from formation_ftc.methods.composed import ComposedScenario, make_loop
from formation_ftc.papers.azizi2009.conditions import d_norms
from formation_ftc.papers.programs import run_loops
from formation_ftc.report.profile import phase
from formation_ftc.sim.loop import ClosedLoop
from formation_ftc.sim.metrics import metrics_dict

__all__ = [
    "run_batch",
    "VARIABLE",
    "PI_GRID",
    "alpha_min_on_grid",
    "alpha2_study",
    "design_numbers",
]

PI_GRID = tuple(round(0.05 * j, 2) for j in range(9))


def alpha_min_on_grid(alpha: np.ndarray, max_err: np.ndarray, e_s: float) -> float | None:
    """Smallest grid alpha whose max error is <= e_s (None if none); ``alpha`` ascending."""
    ok = np.nonzero(np.asarray(max_err) <= e_s)[0]
    return float(alpha[ok[0]]) if ok.size else None


def _interp_alpha(alpha: np.ndarray, max_err: np.ndarray, e_s: float) -> float:
    """alpha at which the (decreasing) simulated max error crosses e_s (linear interpolation)."""
    me = np.asarray(max_err)
    return float(np.interp(e_s, me[::-1], np.asarray(alpha)[::-1]))


#: what :func:`run_batch` may vary: name -> (component, field) of the closed loop (None: the loop)
VARIABLE = {
    "alpha": ("controller", "alpha"),
    "alpha_flfr": ("controller", "alpha_flfr"),
    "seed": (None, "seed"),
}


def _variant(loop: ClosedLoop, values: Mapping[str, Any]) -> ClosedLoop:
    for name, value in values.items():
        slot, field = VARIABLE[name]
        owner: Any = loop if slot is None else getattr(loop, slot)
        new = jnp.asarray(value, dtype=jnp.result_type(getattr(owner, field)))
        changed = dataclasses.replace(owner, **{field: new})
        loop = changed if slot is None else dataclasses.replace(loop, **{slot: changed})
    return loop


def run_batch(
    sc: ComposedScenario, variations: Mapping[str, np.ndarray], grid: tuple[int, int] | None = None
) -> list[dict[str, float]]:
    """Metrics of len(batch) runs of ``sc`` (a scenario of the paper's law on the double-integrator
    plant) that differ only in the given leaves (see :data:`VARIABLE`: ``alpha`` (B, N),
    ``alpha_flfr`` (B,), ``seed`` (B,)), run as one compiled, vmapped program through
    :func:`formation_ftc.papers.programs.run_loops` (leaves shared by every run stay unbatched). Each
    run's metrics also carry ``D_norm_llfr`` / ``D_norm_flfr``: ||D||_2 of eq. (6) from its weights
    (true eps).

    ``grid = (rows, columns)``: run b is cell ``(b // columns, b % columns)`` of a grid (B = rows x
    columns), batched by two nested maps (:func:`formation_ftc.papers.programs.run_loops`): a seed per
    row is batched once per row, and so are the noise draws. Same metrics, in the same order.
    Raises ``RuntimeError`` naming a run that diverged."""
    unknown = set(variations) - set(VARIABLE)
    if unknown:
        raise KeyError(f"unknown variations {sorted(unknown)}; valid: {sorted(VARIABLE)}")
    sizes = {np.asarray(v).shape[0] for v in variations.values()}
    if len(sizes) != 1:
        raise ValueError(f"all variations need the same batch size, got {sizes}")
    (size,) = sizes
    loop = make_loop(sc).validate()
    loops = [
        _variant(loop, {k: np.asarray(v)[b] for k, v in variations.items()}) for b in range(size)
    ]
    if grid is None:
        out = run_loops(loops)
    else:
        rows, cols = (int(g) for g in grid)
        if rows < 1 or cols < 1 or rows * cols != size:
            raise ValueError(f"grid = {grid}: rows x columns must equal the batch size {size}")
        out = run_loops(loops, cols)
        out = jax.tree_util.tree_map(lambda a: np.reshape(a, (size,) + np.shape(a)[2:]), out)
    res = []
    for b, lp in enumerate(loops):
        div = int(out["diverged_step"][b])
        if div >= 0:
            raise RuntimeError(f"batch member {b} diverged at step {div}")
        m = metrics_dict(loop.metrics, [np.asarray(v)[b] for v in out["metrics"]])
        ctl: Any = lp.controller
        m["D_norm_llfr"], m["D_norm_flfr"] = d_norms(
            sc, lp, np.asarray(ctl.alpha), float(np.asarray(ctl.alpha_flfr))
        )
        res.append(m)
    return res


def _llfr(overrides: dict) -> ComposedScenario:
    return cast(ComposedScenario, load_scenario("azizi2009-llfr", overrides))


def alpha2_study(
    overrides: dict, e_s: float, sweep_step: float, seeds: int, seed_window: float, noise: float
) -> dict[str, Any]:
    """The alpha_2 sweep 1.0 ... 10.0 on a ``sweep_step`` grid (x axis only) and the spread over
    ``seeds`` noisy seeds (sigma ``noise`` on e_ij [m] and de_ij/dt [m/s]) of alpha_2 = 1 and a
    +/- ``seed_window`` window of the grid around the noise-free minimum; ``overrides`` apply to every
    scenario (e.g. the horizon)."""
    x_only = {**overrides, "plant.axes": 1, "simulation.record_every": 1000}
    n_grid = round(9.0 / sweep_step) + 1
    alpha_grid = np.round(1.0 + sweep_step * np.arange(n_grid), 10)
    A = np.ones((n_grid, 4))
    A[:, 1] = alpha_grid
    with phase("run"):
        res = run_batch(_llfr(x_only), {"alpha": A})
    max_err = np.array([r["max_err"] for r in res])
    a_min = alpha_min_on_grid(alpha_grid, max_err, e_s)
    center = a_min if a_min is not None else 10.0
    half = round(seed_window / sweep_step)
    win = np.round(center + sweep_step * np.arange(-half, half + 1), 10)
    win = win[(win >= 1.0 - 1e-9) & (win <= 10.0 + 1e-9)]
    per_seed = np.concatenate([[1.0], win])
    noisy = {**x_only, "sensors.position_noise_std": noise, "sensors.velocity_noise_std": noise}
    SA = np.ones((seeds * per_seed.size, 4))
    SA[:, 1] = np.tile(per_seed, seeds)
    SS = np.repeat(np.arange(seeds), per_seed.size)
    with phase("run"):
        # a grid, seeds x weights: each seed's noise is drawn once for its row of weights
        res_s = run_batch(_llfr(noisy), {"alpha": SA, "seed": SS}, (seeds, per_seed.size))
    me_s = np.array([r["max_err"] for r in res_s]).reshape(seeds, per_seed.size)
    amin_seed = np.array([alpha_min_on_grid(win, me_s[j, 1:], e_s) or np.nan for j in range(seeds)])
    edge = [j for j in range(seeds) if not amin_seed[j] > win[0] + 1e-9]
    found = bool(np.any(np.isfinite(amin_seed)))  # a seed met e_s inside the window
    llfr_seed = me_s[:, 0]
    return {
        "alpha_grid": alpha_grid,
        "max_err": max_err,
        "d_norm": np.array([r["D_norm_llfr"] for r in res]),
        "a_min": a_min,
        "a_interp": _interp_alpha(alpha_grid, max_err, e_s),
        "window": win,
        "seed_edge": edge,
        "seed_spread": {
            "seeds": int(seeds),
            "noise_sigma_position_m": noise,
            "noise_sigma_velocity_m_s": noise,
            "alpha2_min_simulated_min": float(np.nanmin(amin_seed)) if found else None,
            "alpha2_min_simulated_max": float(np.nanmax(amin_seed)) if found else None,
            "alpha2_min_simulated_mean": float(np.nanmean(amin_seed)) if found else None,
            "max_err_llfr_min": float(llfr_seed.min()),
            "max_err_llfr_max": float(llfr_seed.max()),
            "max_err_llfr_std": float(llfr_seed.std()),
            "seeds_at_window_edge": edge,
        },
    }


def design_numbers(law: Any, count: int, e_s: float) -> dict[str, Any]:
    """The offline FLFR design (:func:`formation_ftc.design.flfr.design_flfr`) of the law's section
    ``law`` for ``count`` spacecraft and the bound ``e_s`` [m]: its summary numbers (q1, q2, cofactors,
    H_i from A_clp at alpha_2 = 1 and from the nominal A, alpha_2(pi) of eq. (11), the small-gain margin
    gamma_1, the disturbance floor T), the analytic curves alpha_2(e_s) of Fig. 4 and the rows' values."""
    from formation_ftc.components.controllers.azizi2009_llfr import flfr_design

    design = flfr_design(law, count, e_s, PI_GRID)
    a_an: Any = design.alpha  # pi -> alpha_2 (every pi of PI_GRID has one)
    nominal: Any = design.alpha_nominal_H
    coeff, sg = design.coefficients, design.small_gain
    vals = np.array([a_an[p] for p in PI_GRID])
    lin = np.polyfit(1 - np.array(PI_GRID), vals, 1)
    es_grid = np.linspace(0.012, 0.07, 200)
    return {
        **{f"alpha2_analytic_pi_{p:g}": float(a_an[p]) for p in (0.0, 0.15, 0.2, 0.4)},
        "alpha2_analytic_nominal_A": {f"pi_{p:g}": float(v) for p, v in nominal.items()},
        "alpha2_analytic_all_pi": {f"pi_{p:g}": float(v) for p, v in a_an.items()},
        "H1_clp_alpha2_1": design.H,
        "H1_nominal_A": design.H_nominal,
        "q1": coeff.q1,
        "q2": coeff.q2,
        "DET_alpha2_1": coeff.det(1.0),
        "cofactors_C_k2": coeff.f.tolist(),
        "gamma1": sg.gamma1,
        "B_Delta": sg.b_delta,
        "Delta_norm_alpha2_1": design.delta_norm_reference,
        "bound8_alpha2_1": design.bound_at_reference,
        "disturbance_floor_T": design.floor,
        "analytic_by_pi": {p: float(a_an[p]) for p in PI_GRID},
        "nominal_by_pi": dict(nominal),
        "analytic_values": vals,
        "linear_residual": float(np.max(np.abs(np.polyval(lin, 1 - np.array(PI_GRID)) - vals))),
        "certificate": sg.certificate,
        "gamma1_certified": sg.norm is None or sg.norm.certified,
        "es_grid": es_grid,
        "analytic_curves": {
            p: np.array(
                [
                    law.b_eps * (1 - p) * design.H / (coeff.q2 * e) - coeff.q1 / coeff.q2
                    for e in es_grid
                ]
            )
            for p in PI_GRID
        },
    }
