"""Theorem 1 / Theorem 2 conditions of a switched formation (Yang2013 (21), (22), (24), (29)).

For a composed scenario with plant ``switched-formation``, controller ``yang2013-force-torque`` and
supervisor ``switching`` (:mod:`formation_ftc.components.supervisors.switching`):
:func:`design_quantities` computes D, S (Frobenius as printed and induced 2-norm, E001-04), the
dwell-time bounds, the envelope and the initial/new-state bounds; :func:`conditions` (registered for
the switching supervisor: ``formation-ftc check`` states them) turns them into
:class:`formation_ftc.registry.Condition` rows naming the violated inequality when one fails. The
disturbance bounds (1), (4) are verified over the continuous horizon by interval arithmetic
(:func:`disturbance_bounds`); the sampled peaks (:func:`disturbance_peaks`) are shown beside them and
decide alone (basis "sampled") when the enclosure is inconclusive.
"""

from __future__ import annotations

import numpy as np

from formation_ftc.components.actuators.velocity_gain_fault import VelocityFault
from formation_ftc.components.controllers.yang2013_force_torque import Yang2013ForceTorqueSection
from formation_ftc.components.plants.switched_formation import SwitchedFormationSection
from formation_ftc.core.expressions import compile_expression
from formation_ftc.core.interval import IntervalError, enclose_norm
from formation_ftc.design import dwell_time as dw
from formation_ftc.design.dwell_time import Inequality
from formation_ftc.methods.composed import ComposedScenario
from formation_ftc.papers._conditions import exact, informative, sampled_or_verified
from formation_ftc.registry import Condition
from formation_ftc.sim.loop import ClosedLoop

__all__ = [
    "design_quantities",
    "faults",
    "fault_conditions",
    "conditions",
    "disturbance_peaks",
    "disturbance_bounds",
]


def faults(sc: ComposedScenario) -> list[VelocityFault]:
    """The controller faults of the scenario's ``velocity-gain-fault`` actuator (none without one)."""
    return list(getattr(sc.section("actuator"), "faults", []))


def design_quantities(sc: ComposedScenario) -> dict[str, float]:
    """Numbers of Theorem 1 for the scenario (S per ``supervisor.variation_norm``)."""
    d = sc.section("supervisor")
    mats = d.variation_matrices()
    S_fro = dw.max_variation_norm(mats, "frobenius") if mats else 1.0
    S_2 = dw.max_variation_norm(mats, "induced2") if mats else 1.0
    S = S_fro if d.variation_norm == "frobenius" else S_2
    D = dw.disturbance_bound(d.force_bound, d.torque_bound)
    x0 = np.linalg.norm(np.stack([s.vector() for s in sc.section("plant").initial_state]))
    act = d.activation_times()

    def dwell(S: float, **options: float) -> float:
        return dw.dwell_time_bound(
            d.eta, S, d.zeta, D, d.epsilon, d.epsilon1, d.dwell_time, **options
        )

    return {
        "D": D,
        "S": S,
        "S_frobenius": S_fro,
        "S_induced2": S_2,
        "envelope": dw.state_envelope(d.epsilon, S, d.zeta, D),
        "pre_switch_bound": dw.pre_switch_bound(d.epsilon1, d.zeta, D),
        "dwell_time_required": dwell(S),
        "dwell_time_required_frobenius": dwell(S_fro),
        "dwell_time_required_induced2": dwell(S_2),
        "dwell_time_required_proof_S_plus_1": dwell(S, s_offset=1.0),
        "min_activation_time": min(act) if act else float("inf"),
        "initial_state_norm": float(x0),
        "initial_state_bound": dw.initial_state_bound(d.epsilon, S, d.zeta, D),
        "new_state_bound": dw.new_state_bound(d.epsilon2, d.zeta, D),
        "S_eps1_plus_eps2": S * d.epsilon1 + d.epsilon2,
    }


def fault_conditions(sc: ComposedScenario) -> list[tuple[int, Inequality, bool]]:
    """For each fault: (spacecraft, (29) inequality, leaves at the next switch).

    ``t_f`` is the onset; the diagnosis delay is part of dt2 (Sec. 3.2), which is what the flight-side
    supervisor computes from the diagnosis time minus the a-priori delay bound.
    """
    out = []
    d = sc.section("supervisor")
    starts = d.switch_times()
    mats = d.variation_matrices()
    for f in faults(sc):
        j = max(i for i, s in enumerate(starts) if s <= f.onset)
        if j + 1 >= len(starts):
            ineq = Inequality(
                "(eta/2) dt1 - (eta1/2) dt2 >= 0",
                "(29)",
                float("-inf"),
                ">=",
                0.0,
                False,
                detail="fault in the last mode: no switch can remove the faulty spacecraft",
            )
            out.append((f.spacecraft, ineq, False))
            continue
        dt1, dt2 = f.onset - starts[j], starts[j + 1] - f.onset
        ineq = dw.check_condition_29(d.eta, d.eta1, dt1, dt2)
        prev = d.modes[j].members
        S = mats[j]
        leaves = f.spacecraft in prev and not np.any(S[:, prev.index(f.spacecraft)])
        out.append((f.spacecraft, ineq, bool(leaves)))
    return out


def disturbance_peaks(sc: ComposedScenario, n_samples: int = 20001) -> tuple[float, float]:
    """max_t,i |d_i(t)| and |iota_i(t)| on a grid over the horizon (sampled check of the bounds)."""
    t = np.linspace(0.0, sc.simulation.horizon, n_samples)
    plant = sc.section("plant")
    peaks = []
    for texts in (plant.disturbance_force, plant.disturbance_torque):
        worst = 0.0
        for i in range(1, plant.count + 1):
            values = [compile_expression(tx, ("t", "i"))(t=t, i=float(i)) for tx in texts]
            comps = [np.broadcast_to(np.asarray(v), t.shape) for v in values]
            worst = max(worst, float(np.max(np.linalg.norm(np.stack(comps), axis=0))))
        peaks.append(worst)
    return peaks[0], peaks[1]


def disturbance_bounds(
    sc: ComposedScenario, tol: float = 1e-9
) -> tuple[float | None, float | None]:
    """Verified upper bounds of max_t,i |d_i(t)| and |iota_i(t)| over [0, horizon] (None if not enclosed).

    Interval arithmetic (:func:`formation_ftc.core.interval.enclose_norm`): the norm of the 3-vector is
    bounded from the enclosures of its components on sub-intervals, bisected where the bound reaches
    the stated bound times (1 + tol).
    """
    out: list[float | None] = []
    plant, d = sc.section("plant"), sc.section("supervisor")
    horizon = float(sc.simulation.horizon)
    for texts, bound in (
        (plant.disturbance_force, d.force_bound),
        (plant.disturbance_torque, d.torque_bound),
    ):
        components, upper = [str(tx) for tx in texts], float(bound) * (1 + tol)
        try:
            norms = [
                enclose_norm(components, ("t", "i"), 0.0, horizon, upper=upper, i=float(i))
                for i in range(1, plant.count + 1)
            ]
            out.append(max(norms, default=0.0))
        except IntervalError:
            out.append(None)
    return out[0], out[1]


#: Detail of the sampled disturbance checks (a violation found is real; a pass is an estimate).
SAMPLED = (
    "sampled on 20,001 points over the horizon: a violation found is real, a pass is not a proof "
    "(no verified bound between samples)"
)
#: Detail of the verified disturbance checks.
VERIFIED = (
    "verified by interval arithmetic over the continuous horizon: the norm is bounded from outward-"
    "rounded enclosures of its components on sub-intervals (relative tolerance 1e-9); value = sampled "
    "peak on 20,001 points"
)
#: Detail of the closed-form scalar inequalities.
EXACT = "exact: closed-form scalar inequality on the scenario values (tolerance 1e-12 on <= / >=)"


def _cond(ineq: Inequality, detail: str = "") -> Condition:
    text = detail or ineq.detail
    return exact(
        ineq.name,
        f"Yang2013 {ineq.reference}",
        f"{ineq.lhs:.6g}",
        f"{ineq.relation} {ineq.rhs:.6g}",
        bool(ineq.holds),
        f"{text}; {EXACT}" if text else EXACT,
    )


def conditions(sc: ComposedScenario, loop: ClosedLoop | None = None) -> list[Condition]:
    """Conditions of Theorems 1-2 of a switched formation under the laws (12)-(13) (none for other
    compositions: the theorems do not apply); a failing required one names the violated inequality."""
    if not (
        isinstance(sc.section("plant"), SwitchedFormationSection)
        and isinstance(sc.section("controller"), Yang2013ForceTorqueSection)
    ):
        return []
    d = sc.section("supervisor")
    q = design_quantities(sc)
    c = sc.section("controller")
    rate = dw.translational_decay_rate(c.K1, c.K2)
    out: list[Condition] = [
        informative(
            "S = max|S_ij| (Frobenius, as printed) and induced 2-norm",
            "Yang2013 after (20), E001-04",
            f"S_F = {q['S_frobenius']:.4f}, S_2 = {q['S_induced2']:.4f}; D = {q['D']:.4g}",
            f"using {d.variation_norm}",
            None,
            "informative: the two norms of the variation matrices (numpy), shown for E001-04",
        ),
        exact(
            "gains realise eta: 2 x decay rate of e'' + K2 e' + (K1+1) e = 0",
            "Yang2013 (12), (20)",
            f"{2 * rate:.6g} 1/s (K1 = {c.K1:g}, K2 = {c.K2:g})",
            f">= eta = {d.eta:g}",
            bool(2 * rate >= d.eta * (1 - 1e-9)),
            "underdamped loop: rate = K2/2, so K2 = eta (design.dwell_time.gains_for_decay_rate); "
            + EXACT,
        ),
        exact(
            "attitude-rate loop at least as fast: K3 >= eta/2",
            "Yang2013 (13)",
            f"{c.K3:g}",
            f">= {d.eta / 2:g}",
            bool(c.K3 >= d.eta / 2),
            EXACT,
        ),
    ]
    for f in faults(sc):
        growth = -2.0 * dw.translational_decay_rate(c.K1, f.K2_faulty)
        out.append(
            exact(
                f"eta1 bounds the faulty growth of spacecraft {f.spacecraft}",
                "Yang2013 (28)",
                f"{growth:.6g} 1/s (K2f = {f.K2_faulty:g})",
                f"<= eta1 = {d.eta1:g}",
                bool(growth <= d.eta1 * (1 + 1e-9)),
                EXACT,
            )
        )
    out += [_cond(ineq) for ineq in dw.check_epsilons(d.epsilon, d.epsilon1, d.epsilon2, q["S"])]
    dwell = dw.check_dwell_time(
        q["min_activation_time"], d.eta, q["S"], d.zeta, q["D"], d.epsilon, d.epsilon1, d.dwell_time
    )
    out += [
        _cond(
            dwell,
            detail=f"bound {q['dwell_time_required']:.1f} s; with S_2: "
            f"{q['dwell_time_required_induced2']:.1f} s; proof-consistent (S+1): "
            f"{q['dwell_time_required_proof_S_plus_1']:.1f} s (E001-07)",
        ),
        _cond(dw.check_initial_state(q["initial_state_norm"], d.epsilon, q["S"], d.zeta, q["D"])),
    ]
    for j, m in enumerate(d.modes):
        for ns in m.new_states:
            who = f"spacecraft {ns.spacecraft} joining mode {j + 1}"
            norm = float(np.linalg.norm(ns.vector()))
            out.append(_cond(dw.check_new_state(norm, d.epsilon2, d.zeta, q["D"], who=who)))
    d_peak, i_peak = disturbance_peaks(sc)
    d_up, i_up = disturbance_bounds(sc)
    for name, ref, peak, up, bound in (
        ("|d_i(t)| <= d_bar", "Yang2013 (1)", d_peak, d_up, d.force_bound),
        ("|iota_i(t)| <= iota_bar", "Yang2013 (4)", i_peak, i_up, d.torque_bound),
    ):
        limit = bound * (1 + 1e-9)
        reached = f" (reached {up:.6g})" if up is not None else ""
        out.append(
            sampled_or_verified(
                name,
                ref,
                f"{peak:.4g} (sampled peak)",
                f"<= {bound:g}",
                SAMPLED if peak > limit else None,
                (f"; verified bound {up:.8g}", VERIFIED)
                if up is not None and up <= limit
                else None,
                f"the interval bound could not prove it{reached}; {SAMPLED}",
            )
        )
    for scn, ineq, leaves in fault_conditions(sc):
        out.append(
            exact(
                f"spacecraft {scn} leaves at the next switch (Case 1/2)",
                "Yang2013 Thm 2",
                str(leaves),
                "True",
                leaves,
                "exact: structural zero pattern of the variation matrix",
            )
        )
        out.append(_cond(ineq, detail=f"spacecraft {scn}: {ineq.detail}"))
    return out
