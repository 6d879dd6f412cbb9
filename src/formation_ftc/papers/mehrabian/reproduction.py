"""Reproduction ``mehrabian``: the three FDI-imperfection cases of Sec. V over 20 seeds, Figs. 2-5.

Declared in ``study.toml``; the seed study (the 3 cases x 20 seeds as one vmapped grid, the
diffusive-law variant and the figure runs of seed 1) is :func:`formation_ftc.papers.mehrabian.seed_study.
case_study`; :func:`quantities` computes the comparisons' numbers and the design quantities.
"""

from __future__ import annotations

import numpy as np

from formation_ftc.papers._study import Run, read_study, study
from formation_ftc.papers.mehrabian.seed_study import CASES, SEEDS, _mn, _ms, _mx, case_study

__all__ = ["REPRODUCTION", "CASES", "SEEDS", "DESIGN_REFERENCE", "quantities"]

#: closed-form design quantities of eqs. (13)-(15), (11) and the literal law's consensus damping
DESIGN_REFERENCE = read_study("mehrabian")["reproduction"]["constants"]["design_reference"]


def quantities(runs: dict[str, Run], constants: dict) -> dict:
    """The numbers ``study.toml`` reads (``constants``: the seeds, the design references)."""
    from formation_ftc.methods.composed import make_loop
    from formation_ftc.papers.mehrabian import conditions

    seeds = list(constants["seeds"])
    st = case_study(seeds, constants["overrides"])
    M, div, valid, scns = st["M"], st["div"], st["valid"], st["scenarios"]
    A, B, C, deg = 0, 1, 2, np.rad2deg
    dt, finite = scns[0].simulation.dt, div < 0
    okf, oka = valid["fault_window"].all(axis=0), valid["assessment_window"].all(axis=0)
    sync, track = M["sync_err_rms_fault_window"][:, okf], M["track_err_rms_fault_window"][:, okf]
    yaw_sp = deg(M["spread_max_yaw_assessment_window"])[:, oka]
    roll_sp = deg(M["spread_max_roll_assessment_window"])[:, oka]
    abs_yaw = deg(M["abs_max_yaw_assessment_window"])[:, oka]
    pitch, pitch_fw = deg(M["abs_max_pitch_run"]), deg(M["abs_max_pitch_fault_window"])

    def diverged(cases) -> str:
        bad = [(seeds[k], div[i, k] * dt) for i in cases for k in np.flatnonzero(div[i] >= 0)]
        text = "; ".join(f"seed {sd} left the admissible set at t = {t:.2f} s" for sd, t in bad)
        return f"; {text}" if text else ""

    q = {"summary": st["summary"], "n_seeds": len(seeds), "scenarios": [CASES[c][0] for c in "ABC"]}
    q |= {"seeds": seeds, "first_seed": seeds[0], "last_seed": seeds[-1]}
    q |= {f"dataset_{c}": st["datasets"][i] for i, c in enumerate("ABC")}
    window = st["windows"]["fault_window"]
    q |= {f"attitudes_{c}": {"title": f"Fig. {CASES[c][1]}: {CASES[c][2]} (seed 1)", "window": window} for c in "ABC"}  # fmt: skip
    q["sync_by_case"] = {f"{k} ({CASES[k][0].split('-', 1)[1]})": M["sync_err_rms_fault_window"][i] for i, k in enumerate("ABC")}  # fmt: skip
    q["seed_spread_labels"] = {"ylabel": "sync error RMS, 40-240 s [rad]", "title": f"Synchronisation error over {len(seeds)} seeds"}  # fmt: skip
    q |= {"sync_ratio": _ms(sync[B] / sync[A]), "sync_A": _ms(sync[A]), "sync_B": _ms(sync[B])}
    q |= {"sync_ratio_max": _mx(sync[B] / sync[A]), "track_ratio_max": _mx(track[B] / track[A])}
    q |= {"track_ratio": _ms(track[B] / track[A]), "track_A": _ms(track[A])}
    q["track_B"] = _ms(track[B])
    q |= {"c_fw_finite": int(valid["fault_window"][C].sum()), "c_fw_all": bool(valid["fault_window"][C].all())}  # fmt: skip
    q |= {"fault_window_end": st["ends"]["fault_window"], "c_fw_theta": _mx(pitch_fw[C])}
    q["c_fw_theta_finite"] = _mx(pitch_fw[C][valid["fault_window"][C]])
    q |= {"c_finite": int(finite[C].sum()), "c_all": bool(finite[C].all())}
    q["c_theta"] = _mx(pitch[C])
    q |= {"horizon": scns[0].simulation.horizon, "c_theta_finite": _mx(pitch[C][finite[C]])}
    q |= {"c_diverged": diverged([C]), "all_diverged": diverged([A, B, C])}
    q |= {"roll_ratio": _ms(roll_sp[C] / roll_sp[B]), "roll_C": _ms(roll_sp[C], ".1f")}
    q["roll_ratio_min"] = _mn(roll_sp[C] / roll_sp[B])
    q["abs_yaw_CB"] = _ms(abs_yaw[C] / abs_yaw[B])
    q |= {"yaw_spread_CB": _ms(yaw_sp[C] / yaw_sp[B]), "abs_yaw_CB_min_diff": _mn(abs_yaw[C] - abs_yaw[B])}  # fmt: skip
    q |= {"yaw_spread_CB_min_diff": _mn(yaw_sp[C] - yaw_sp[B]), "yaw_spread_BA": _ms(yaw_sp[B] / yaw_sp[A])}  # fmt: skip
    q["yaw_spread_BA_max"] = _mx(yaw_sp[B] / yaw_sp[A])
    q["abs_yaw_BA"] = _ms(abs_yaw[B] / abs_yaw[A])
    q |= {"abs_yaw_BA_max": _mx(abs_yaw[B] / abs_yaw[A]), "n_finite": int(finite.sum())}
    q |= {"n_runs": finite.size, "all_finite": bool(finite.all()), "theta_all": _mx(pitch)}
    q["theta_finite"] = _mx(pitch[finite])
    dq, ref = conditions.design_quantities(20.0, 0.16, 0.001, 0.86, 0.6), DESIGN_REFERENCE
    q |= {"dq": dq, "dq_R": dq.R, "dq_K_minus": dq.K_minus, "ref_R": ref["R"]}
    q |= {"dq_cond11": dq.cond11, "ref_cond11": ref["cond11"]}
    q |= {"dq_damping": dq.consensus_damping_literal, "ref_damping": ref["damping"]}
    q["sum_Q_text"] = ", ".join(f"{x:.4g}" for x in dq.sum_Q_jn)
    q["sum_Q_clauses"] = tuple(("rel<=", float(x), r, 2e-3) for x, r in zip(dq.sum_Q_jn, ref["sum_Q_jn"], strict=True))  # fmt: skip
    q |= {"sum_Q_reference": tuple(ref["sum_Q_jn"]), "Q_reference": tuple(ref["Q_j"])}
    q["Q_text"] = ", ".join(f"{x:.4g}" for x in dq.Q_j)
    q["Q_clauses"] = tuple(("rel<=", float(x), r, 2e-3) for x, r in zip(dq.Q_j, ref["Q_j"], strict=True))  # fmt: skip
    lyapunov = (conditions.lyapunov_matrix(d * np.eye(3), 20.0, 0.16, 0.001) for d in (10, 20))
    q["P_min"] = min(np.linalg.eigvalsh(P).min() for P in lyapunov)
    roll_d = deg(st["Md"]["spread_max_roll_assessment_window"])
    q |= {"alt_seeds": seeds[:3], "diffusive_C": ", ".join(f"{v:.2f}" for v in roll_d[1])}
    q |= {"diffusive_A": ", ".join(f"{v:.2f}" for v in roll_d[0])}
    q |= {"literal_C": roll_sp[C][:3].round(1).tolist(), "diffusive_ratio_max": _mx(roll_d[1] / roll_d[0])}  # fmt: skip
    q["diffusive_finite"] = bool(np.all(st["divd"] < 0))
    return q | {"checks": conditions.check(scns[B], make_loop(scns[B]))}


REPRODUCTION = study("mehrabian", quantities)
