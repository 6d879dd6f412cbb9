"""Theorem 1 / Theorem 2 conditions of a ``yang2013`` scenario (Yang2013 (21), (22), (24), (29)).

:func:`design_quantities` computes D, S (Frobenius as printed and induced 2-norm, E001-04), the
dwell-time bounds, the envelope and the initial/new-state bounds; :func:`check` turns them into
:class:`formation_ftc.registry.Condition` rows naming the violated inequality when one fails.
"""

from __future__ import annotations

import numpy as np

from formation_ftc.core.expressions import compile_expression
from formation_ftc.design import dwell_time as dw
from formation_ftc.design.dwell_time import Inequality
from formation_ftc.papers.yang2013.schema import Yang2013Scenario
from formation_ftc.registry import Condition

__all__ = ["design_quantities", "fault_conditions", "check", "disturbance_peaks"]


def design_quantities(sc: Yang2013Scenario) -> dict[str, float]:
    """Numbers of Theorem 1 for the scenario (S per ``design.variation_norm``)."""
    d = sc.design
    mats = sc.variation_matrices()
    S_fro = dw.max_variation_norm(mats, "frobenius") if mats else 1.0
    S_2 = dw.max_variation_norm(mats, "induced2") if mats else 1.0
    S = S_fro if d.variation_norm == "frobenius" else S_2
    D = dw.disturbance_bound(sc.disturbance.force_bound, sc.disturbance.torque_bound)
    x0 = np.linalg.norm(np.stack([s.vector() for s in sc.initial_state]))
    act = sc.activation_times()
    return {
        "D": D,
        "S": S,
        "S_frobenius": S_fro,
        "S_induced2": S_2,
        "envelope": dw.state_envelope(d.epsilon, S, d.zeta, D),
        "pre_switch_bound": dw.pre_switch_bound(d.epsilon1, d.zeta, D),
        "dwell_time_required": dw.dwell_time_bound(d.eta, S, d.zeta, D, d.epsilon, d.epsilon1, d.dwell_time),
        "dwell_time_required_frobenius": dw.dwell_time_bound(d.eta, S_fro, d.zeta, D, d.epsilon,
                                                             d.epsilon1, d.dwell_time),
        "dwell_time_required_induced2": dw.dwell_time_bound(d.eta, S_2, d.zeta, D, d.epsilon,
                                                            d.epsilon1, d.dwell_time),
        "dwell_time_required_proof_S_plus_1": dw.dwell_time_bound(d.eta, S, d.zeta, D, d.epsilon,
                                                                  d.epsilon1, d.dwell_time, s_offset=1.0),
        "min_activation_time": min(act) if act else float("inf"),
        "initial_state_norm": float(x0),
        "initial_state_bound": dw.initial_state_bound(d.epsilon, S, d.zeta, D),
        "new_state_bound": dw.new_state_bound(d.epsilon2, d.zeta, D),
        "S_eps1_plus_eps2": S * d.epsilon1 + d.epsilon2,
    }


def fault_conditions(sc: Yang2013Scenario) -> list[tuple[int, Inequality, bool]]:
    """For each fault: (spacecraft, (29) inequality, leaves at the next switch).

    ``t_f`` is the onset; the diagnosis delay is part of dt2 (Sec. 3.2), which is what the flight-side
    supervisor computes from the diagnosis time minus the a-priori delay bound.
    """
    out = []
    starts = sc.switch_times()
    mats = sc.variation_matrices()
    for f in sc.faults:
        j = max(i for i, s in enumerate(starts) if s <= f.onset)
        if j + 1 >= len(starts):
            ineq = Inequality("(eta/2) dt1 - (eta1/2) dt2 >= 0", "(29)", float("-inf"), ">=", 0.0, False,
                              detail="fault in the last mode: no switch can remove the faulty spacecraft")
            out.append((f.spacecraft, ineq, False))
            continue
        dt1, dt2 = f.onset - starts[j], starts[j + 1] - f.onset
        ineq = dw.check_condition_29(sc.design.eta, sc.design.eta1, dt1, dt2)
        prev = sc.modes[j].members
        S = mats[j]
        leaves = f.spacecraft in prev and not np.any(S[:, prev.index(f.spacecraft)])
        out.append((f.spacecraft, ineq, bool(leaves)))
    return out


def disturbance_peaks(sc: Yang2013Scenario, n_samples: int = 20001) -> tuple[float, float]:
    """max_t,i |d_i(t)| and |iota_i(t)| on a grid over the horizon (sampled check of the bounds)."""
    t = np.linspace(0.0, sc.simulation.horizon, n_samples)
    peaks = []
    for texts in (sc.disturbance.force, sc.disturbance.torque):
        worst = 0.0
        for i in range(1, sc.spacecraft.count + 1):
            comps = [np.broadcast_to(np.asarray(compile_expression(tx, ("t", "i"))(t=t, i=float(i))), t.shape)
                     for tx in texts]
            worst = max(worst, float(np.max(np.linalg.norm(np.stack(comps), axis=0))))
        peaks.append(worst)
    return peaks[0], peaks[1]


#: Detail of the sampled disturbance checks (a violation found is real; a pass is an estimate).
SAMPLED = ("sampled on 20,001 points over the horizon: a violation found is exact, a pass is an estimate "
           "(not a verified bound between samples)")
#: Detail of the closed-form scalar inequalities.
EXACT = "exact: closed-form scalar inequality on the scenario values (tolerance 1e-12 on <= / >=)"


def _cond(ineq: Inequality, required: bool = True, detail: str = "") -> Condition:
    text = detail or ineq.detail
    return Condition(name=ineq.name, reference=f"Yang2013 {ineq.reference}", value=f"{ineq.lhs:.6g}",
                     requirement=f"{ineq.relation} {ineq.rhs:.6g}", holds=bool(ineq.holds), required=required,
                     detail=f"{text}; {EXACT}" if text else EXACT)


def check(sc: Yang2013Scenario) -> list[Condition]:
    """Conditions of Theorems 1-2; a failing required one names the violated inequality."""
    d = sc.design
    q = design_quantities(sc)
    out: list[Condition] = []
    out.append(Condition(
        name="S = max|S_ij| (Frobenius, as printed) and induced 2-norm", reference="Yang2013 after (20), E001-04",
        value=f"S_F = {q['S_frobenius']:.4f}, S_2 = {q['S_induced2']:.4f}; D = {q['D']:.4g}",
        requirement=f"using {d.variation_norm}", holds=None, required=False))
    c = sc.controller
    rate = dw.translational_decay_rate(c.K1, c.K2)
    out.append(Condition(
        name="gains realise eta: 2 x decay rate of e'' + K2 e' + (K1+1) e = 0", reference="Yang2013 (12), (20)",
        value=f"{2 * rate:.6g} 1/s (K1 = {c.K1:g}, K2 = {c.K2:g})", requirement=f">= eta = {d.eta:g}",
        holds=bool(2 * rate >= d.eta * (1 - 1e-9)), required=True,
        detail="underdamped loop: rate = K2/2, so K2 = eta (design.dwell_time.gains_for_decay_rate); " + EXACT))
    out.append(Condition(
        name="attitude-rate loop at least as fast: K3 >= eta/2", reference="Yang2013 (13)",
        value=f"{c.K3:g}", requirement=f">= {d.eta / 2:g}", holds=bool(c.K3 >= d.eta / 2), required=True,
        detail=EXACT))
    for f in sc.faults:
        growth = -2.0 * dw.translational_decay_rate(c.K1, f.K2_faulty)
        out.append(Condition(
            name=f"eta1 bounds the faulty growth of spacecraft {f.spacecraft}", reference="Yang2013 (28)",
            value=f"{growth:.6g} 1/s (K2f = {f.K2_faulty:g})", requirement=f"<= eta1 = {d.eta1:g}",
            holds=bool(growth <= d.eta1 * (1 + 1e-9)), required=True, detail=EXACT))
    for ineq in dw.check_epsilons(d.epsilon, d.epsilon1, d.epsilon2, q["S"]):
        out.append(_cond(ineq))
    out.append(_cond(dw.check_dwell_time(q["min_activation_time"], d.eta, q["S"], d.zeta, q["D"], d.epsilon,
                                         d.epsilon1, d.dwell_time),
                     detail=f"bound {q['dwell_time_required']:.1f} s; with S_2: "
                            f"{q['dwell_time_required_induced2']:.1f} s; proof-consistent (S+1): "
                            f"{q['dwell_time_required_proof_S_plus_1']:.1f} s (E001-07)"))
    out.append(_cond(dw.check_initial_state(q["initial_state_norm"], d.epsilon, q["S"], d.zeta, q["D"])))
    for j, m in enumerate(sc.modes):
        for ns in m.new_states:
            out.append(_cond(dw.check_new_state(float(np.linalg.norm(ns.vector())), d.epsilon2, d.zeta, q["D"],
                                                who=f"spacecraft {ns.spacecraft} joining mode {j + 1}")))
    d_peak, i_peak = disturbance_peaks(sc)
    out.append(Condition(name="|d_i(t)| <= d_bar (sampled)", reference="Yang2013 (1)", value=f"{d_peak:.4g}",
                         requirement=f"<= {sc.disturbance.force_bound:g}",
                         holds=bool(d_peak <= sc.disturbance.force_bound * (1 + 1e-9)), required=True,
                         detail=SAMPLED))
    out.append(Condition(name="|iota_i(t)| <= iota_bar (sampled)", reference="Yang2013 (4)", value=f"{i_peak:.4g}",
                         requirement=f"<= {sc.disturbance.torque_bound:g}",
                         holds=bool(i_peak <= sc.disturbance.torque_bound * (1 + 1e-9)), required=True,
                         detail=SAMPLED))
    for scn, ineq, leaves in fault_conditions(sc):
        out.append(Condition(
            name=f"spacecraft {scn} leaves at the next switch (Case 1/2)", reference="Yang2013 Thm 2",
            value=str(leaves), requirement="True", holds=leaves, required=True,
            detail="exact: structural zero pattern of the variation matrix"))
        out.append(_cond(ineq, detail=f"spacecraft {scn}: {ineq.detail}"))
    return out
