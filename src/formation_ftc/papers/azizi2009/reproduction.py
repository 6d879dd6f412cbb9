"""Reproduction ``azizi2009``: scenarios (a)-(c), the alpha_2 sweep, the analytic FLFR design, the
seed spread, figures 2-4 and the paper-vs-ours table (errata E004-* in docs/errata.md).

Declared in ``study.toml``; :func:`quantities` computes its numbers: the offline design, a run with the
analytic alpha_2 from t = 0, and the alpha_2 sweep and the seed spread
(:mod:`formation_ftc.papers.azizi2009.alpha2_study`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from formation_ftc.papers._study import Run, study
from formation_ftc.papers.azizi2009.alpha2_study import alpha2_study, design_numbers

__all__ = ["REPRODUCTION", "quantities"]

#: Fig. 2's panels: title -> run; the summary's effort keys per run
_FIG2 = {"(a) fault-free": "fault-free", "(b) LLFR, alpha_2 = 1": "llfr"}
_FIG2 |= {"(c) FLFR, alpha_2 = 6": "alpha2-6", "(d) FLFR, alpha_2 = 10": "alpha2-10"}
_EFFORT = {"fault-free": "fault_free", "llfr": "alpha2_1", "alpha2-6": "alpha2_6"}
_EFFORT |= {"alpha2-10": "alpha2_10"}


def quantities(runs: dict[str, Run], constants: dict) -> dict:
    """The numbers ``study.toml`` reads (``constants``: e_s, the sweep step, the seed spread's size,
    the published values)."""
    from formation_ftc.api import load_scenario
    from formation_ftc.methods.composed import make_loop
    from formation_ftc.papers.azizi2009.conditions import conditions
    from formation_ftc.papers.programs import simulate
    from formation_ftc.report.profile import phase

    c, e_s = constants, constants["e_s"]
    m = {name.removeprefix("azizi2009-"): r.metrics for name, r in runs.items()}
    ds = {name.removeprefix("azizi2009-"): r.dataset for name, r in runs.items()}
    sc_llfr, sc_sv = runs["azizi2009-llfr"].scenario, runs["azizi2009-flfr"].scenario
    hz = {"simulation.horizon": float(sc_llfr.simulation.horizon)}
    q = design_numbers(sc_llfr.section("controller"), sc_llfr.section("plant").count, e_s)
    a0 = q["alpha2_analytic_pi_0"]
    with phase("run"):
        over = {**hz, "plant.axes": 1, "controller.alpha": [1.0, a0, 1.0, 1.0]}
        _, analytic = simulate(load_scenario("azizi2009-llfr", over))
    q["max_err_analytic_alpha2_pi_0"] = analytic["max_err"]
    st = alpha2_study(hz, e_s, c["sweep_step"], c["seeds"], c["seed_window"], c["noise_sigma"])
    q |= {k: st[k] for k in ("alpha_grid", "d_norm", "a_min", "a_interp", "seed_spread")}
    q |= {"alpha2_min_simulated": st["a_min"], "alpha2_min_simulated_interpolated": st["a_interp"]}
    q |= {"max_err_fault_free": m["fault-free"]["max_err"], "max_err_llfr": m["llfr"]["max_err"]}
    q |= {"supervisor_t_flfr": m["flfr"]["t_flfr"]}
    loop_sv: Any = make_loop(sc_sv)  # the supervised run's loop: its FLFR weight, the conditions
    q["supervisor_alpha2"] = float(np.asarray(loop_sv.controller.alpha_flfr))
    q["supervisor_max_err_after_settle"] = m["flfr"]["max_err_after_flfr"]
    q |= {"supervisor_max_err": m["flfr"]["max_err"], "sweep_max_err": st["max_err"]}
    q |= {"max_err_at_10": st["max_err"][-1], "d_norm_at_10": st["d_norm"][-1]}
    q["a_min_v"] = np.nan if st["a_min"] is None else st["a_min"]
    q["llfr_off"] = 100 * abs(q["max_err_llfr"] - c["llfr_published"]) / c["llfr_published"]
    q["llfr_x099"] = 0.99 * q["max_err_llfr"]
    q["analytic"] = [
        {"p": a["pi"], "pub": a["alpha2"]}
        | {"value": q["analytic_by_pi"][a["pi"]], "nominal": q["nominal_by_pi"][a["pi"]]}
        for a in c["analytic_published"]
    ]
    q["analytic_text"] = " > ".join(f"{v:.2f}" for v in q["analytic_values"][[0, 3, 4, 8]])
    q["nominal_0"] = q["nominal_by_pi"][0.0]
    t_cmp = q["t_cmp"] = min(100.0, hz["simulation.horizon"])
    E = {k: ds[k]["effort"].sel(axis="x").sel(time=t_cmp, method="nearest").values for k in _EFFORT}
    q["efforts_at"] = {_EFFORT[k]: [float(v) for v in E[k]] for k in _EFFORT}
    cases = ("llfr", "alpha2-6", "alpha2-10")
    e2, others = [E[k][1] for k in cases], [[E[k][j] for k in cases] for j in (0, 2, 3)]
    q["effort_text"] = f"E_x2({t_cmp:g} s) = " + " > ".join(f"{v:.1f}" for v in e2)
    q["effort_text"] += "; E_x1 = " + " < ".join(f"{v:.1f}" for v in others[0])
    q["effort_clauses"] = (("decreasing", e2), *(("decreasing", [-v for v in o]) for o in others))
    x_effort = {k: (ds[k]["time"].values, ds[k]["effort"].sel(axis="x").values) for k in _EFFORT}
    q["efforts"] = [(title, *x_effort[k]) for title, k in _FIG2.items()]
    edge, win = st["seed_edge"], st["window"]
    narrow = f"seeds {edge}: minimum alpha_2 at/below the window edge {win[0]} (window too narrow)"
    q["edge_note"] = narrow if edge else ""
    q["scenarios"] = ["azizi2009-fault-free", "azizi2009-llfr", "azizi2009-flfr"]
    q["seeds"] = sorted({0, *range(int(c["seeds"]))})
    return q | {"checks": conditions(sc_sv, loop_sv)}


REPRODUCTION = study("azizi2009", quantities)
