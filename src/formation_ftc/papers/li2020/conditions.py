"""Conditions of Li et al. 2020's theorems for composed scenarios whose controller is
``li2020-adaptive`` (Thm 1 over a ``graph`` network, Thm 2 over a ``delayed-graph``) or ``sir-ftc``
(the baseline of Sec. IV-D); registered by :mod:`.registration` with
:func:`~formation_ftc.methods.composed.register_conditions`:

* graph balance (Thms 1-2 assume it; the printed C is NOT balanced, E000-07) with row/column sums;
* strong connectivity (informative);
* delay conditions (Thm 2): T_ij(t) >= 0 for every printed pair and dT_ij/dt < 1 (eq. (46)). They are
  *verified* over the continuous horizon by interval arithmetic (:mod:`formation_ftc.core.interval`:
  enclosures of T and dT/dt); the values shown are sampled at every simulation step
  (:func:`~formation_ftc.components.networks.delayed_graph.delay_statistics`, ``jax.jacfwd`` for the
  rate), and when the enclosure is inconclusive the condition falls back to that sample (basis
  "sampled": a violation found is real, a pass is unproven). That every used delay stays in
  [0, max_delay] is checked when the network is built (the history holds max_delay seconds);
* gain/delay coupling (47): rho = 1/(1 - max h_ij), lambda_i > (rho - 1)/2 sum_j c_ij;
* k_i > 0 (Lemma 2), d_hat_i(0) > 0, sigma integrable (eq. (11));
* sign of the d_hat tanh term consistent with the proof (E000-04);
* Lemma 3 constant r* = x*(1 - tanh x*), e^{-2x*} + 1 - 2x* = 0.

A ``li2020-adaptive`` law over another network (none, or a graph that loses links) is outside the
theorems: no condition.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache
from itertools import permutations

import numpy as np

from formation_ftc.components.networks.delayed_graph import DelayStats, delay_statistics
from formation_ftc.core.graph import balance_report, is_strongly_connected
from formation_ftc.core.interval import IntervalError, enclose, enclose_derivative
from formation_ftc.methods.composed import ComposedScenario, per_spacecraft
from formation_ftc.papers._conditions import exact, fmt_list, informative, sampled_or_verified
from formation_ftc.registry import Condition
from formation_ftc.sim.loop import ClosedLoop

__all__ = ["DelayBounds", "delay_stats", "delay_bounds", "law_of", "lemma3_constant", "check"]

#: network type -> theorem of the ``li2020-adaptive`` law over it
THEOREMS = {"graph": "thm1", "delayed-graph": "thm2"}


def law_of(scenario: ComposedScenario) -> str | None:
    """'thm1', 'thm2' or 'sir-ftc': the Li2020 law a composed scenario flies (None: none of them)."""
    controller = scenario.type_of("controller")
    if controller == "sir-ftc":
        return "sir-ftc"
    if controller == "li2020-adaptive":
        return THEOREMS.get(str(scenario.type_of("network")))
    return None


def _texts(scenario: ComposedScenario) -> tuple[tuple[str, ...], ...] | None:
    delays = getattr(scenario.section("network"), "delays", None)
    return None if delays is None else tuple(tuple(str(x) for x in row) for row in delays)


def delay_stats(scenario: ComposedScenario) -> list[DelayStats]:
    """Delay extremes and rates sampled at every step for every off-diagonal entry of
    ``network.delays`` (empty without delays)."""
    texts = _texts(scenario)
    if texts is None:
        return []
    sim = scenario.simulation
    return list(delay_statistics(texts, float(sim.horizon), float(sim.dt)))


def lemma3_constant() -> tuple[float, float]:
    """(x*, r*) of Lemma 3: e^{-2x} + 1 - 2x = 0, r* = x*(1 - tanh x*)."""
    import scipy.optimize  # here, not at import: loading the plug-in does not need it (about 0.4 s)

    x = scipy.optimize.brentq(lambda x: math.exp(-2 * x) + 1 - 2 * x, 0.1, 2.0, xtol=1e-15)
    return x, x * (1 - math.tanh(x))


#: How the delay values shown are computed (the simulation reads the delays only at these times).
GRID = (
    "sampled at every simulation step over the horizon (values and d/dt by automatic differentiation): "
    "a violation found is real, a pass is not a proof"
)
#: How the delay conditions are verified.
INTERVAL = (
    "verified by interval arithmetic over the continuous horizon (outward-rounded enclosures of T and "
    "dT/dt on 4,096 sub-intervals, bisected where inconclusive); values shown are sampled at every step"
)
#: How the conditions on the scenario's numbers are decided.
VALUES = "exact: comparison of the scenario values"


@dataclass(frozen=True)
class DelayBounds:
    """Verified bounds of one delay over [0, horizon]: ``value_lo <= T_ij(t)`` and ``dT_ij/dt <= rate_hi``
    (``None`` in a field when the interval evaluation could not enclose the expression)."""

    pair: tuple[int, int]
    value_lo: float | None
    rate_hi: float | None


@lru_cache(maxsize=256)
def _delay_bound(
    text: str, i: int, j: int, horizon: float, rate_target: float
) -> tuple[float | None, float | None]:
    names = ("t", "i", "j")
    lo: float | None
    hi: float | None
    try:
        lo, _ = enclose(text, names, 0.0, horizon, lower=0.0, i=float(i + 1), j=float(j + 1))
    except IntervalError:
        lo = None
    try:
        _, hi = enclose_derivative(
            text, names, 0.0, horizon, upper=rate_target, i=float(i + 1), j=float(j + 1)
        )
    except IntervalError:
        hi = None
    return lo, hi


def delay_bounds(
    scenario: ComposedScenario, rate_target: float = 1.0
) -> dict[tuple[int, int], DelayBounds]:
    """Verified lower bound of T_ij and upper bound of dT_ij/dt over [0, horizon] for every off-diagonal
    pair (interval arithmetic; the rate enclosure is refined until it is below ``rate_target`` where a
    few bisections suffice)."""
    d = _texts(scenario)
    if d is None:
        return {}
    horizon = float(scenario.simulation.horizon)
    return {
        (i, j): DelayBounds((i, j), *_delay_bound(d[i][j], i, j, horizon, float(rate_target)))
        for i, j in permutations(range(len(d)), 2)  # the off-diagonal pairs, row by row
    }


def _rate_target(lam: np.ndarray, C: np.ndarray) -> float:
    """Largest h with lambda_i > h/(1 - h)/2 sum_j c_ij for all i (eq. (47)), capped at 1."""
    s = C.sum(axis=1)
    with np.errstate(divide="ignore"):
        q = np.where(s > 0, 2.0 * lam / np.where(s > 0, s, 1.0), np.inf)
    qmin = float(np.min(q)) if q.size else math.inf
    return 1.0 if not qmin > 0 or math.isinf(qmin) else min(1.0, qmin / (1.0 + qmin))


def _worst_bound(bounds: list[DelayBounds]) -> float | None:
    """max rate_hi over the pairs, None if one is missing (no verified bound)."""
    his = [b.rate_hi for b in bounds]
    return None if None in his else max((float(h) for h in his if h is not None), default=0.0)


def _delay_conditions(
    scenario: ComposedScenario, C: np.ndarray, lam: np.ndarray
) -> list[Condition]:
    """Delay conditions of Theorem 2: verified by interval arithmetic, else sampled (see module doc)."""
    stats = delay_stats(scenario)
    used_stats = [st for st in stats if C[st.pair] > 0]
    target = _rate_target(lam, C)
    vb_used = delay_bounds(scenario, rate_target=target * (1 - 1e-9) if target < 1 else 1.0)
    vb_all = delay_bounds(scenario)
    # T >= 0 on every printed pair
    neg = [f"sampled: {st.name} < 0 at t = {st.t_min:.6g} s" for st in stats if st.value_min < 0]
    lows = [vb_all[st.pair].value_lo for st in stats]
    lo_all = min((v for v in lows if v is not None), default=math.inf)
    out = [
        sampled_or_verified(
            "delays non-negative",
            "Li2020 Sec. III-B",
            ", ".join(f"min {st.name} = {st.value_min:.4g} s" for st in used_stats),
            ">= 0 on every pair",
            "; ".join([*neg, GRID]) if neg else None,
            (f"; verified T >= {lo_all:.4g} s on every pair", INTERVAL)
            if all(v is not None and v >= 0 for v in lows)
            else None,
            "sampled (unproven; the interval enclosure reaches below 0): " + GRID,
        )
    ]
    # dT/dt <= h < 1 on the used edges (eq. (46))
    worst = max(used_stats, key=lambda st: st.rate_max) if used_stats else None
    h = worst.rate_max if worst else 0.0
    h_up = _worst_bound([vb_used[st.pair] for st in used_stats])
    h_proved = h_up is not None and h_up < 1
    out.append(
        sampled_or_verified(
            "delay rate bound (used edges)",
            "Li2020 eq. (46); E000-15",
            "no edges"
            if worst is None
            else f"max dT/dt = {h:.4f} ({worst.name} at t = {worst.t_rate_max:.4g} s); "
            + ", ".join(f"{st.name}: {st.rate_max:.4f}" for st in used_stats),
            "h_ij < 1",
            "sampled: the rate reaches 1 at a step; " + GRID if h >= 1 else None,
            (f"; verified h <= {h_up:.6g}", INTERVAL) if h_proved else None,
            f"sampled (unproven; the rate enclosure reaches {h_up}): " + GRID,
        )
    )
    if stats:
        wa = max(stats, key=lambda st: st.rate_max)
        ha_up = _worst_bound([vb_all[st.pair] for st in stats])
        row = sampled_or_verified(
            "delay rate bound (all printed delays)",
            "Li2020 Sec. IV-A; E000-15",
            f"max dT/dt = {wa.rate_max:.4f} ({wa.name} at t = {wa.t_rate_max:.4g} s)",
            "< 1",
            "sampled: the rate reaches 1 at a step; " + GRID if wa.rate_max >= 1 else None,
            (f"; verified <= {ha_up:.6g}", INTERVAL) if ha_up is not None and ha_up < 1 else None,
            "sampled (unproven by the interval enclosure): " + GRID,
            required=False,
        )
        unused = "not required (unused delays do not enter the closed loop); "
        out.append(replace(row, detail=unused + row.detail))
    if h < 1:
        rows = C.sum(axis=1)

        def margin_at(hh: float) -> np.ndarray:
            rho = 1.0 / (1.0 - hh)  # Li2020 eq. (47)
            return lam - (rho - 1.0) / 2.0 * rows

        margin = margin_at(h)
        rho = 1.0 / (1.0 - h)
        slack = 1e-12 * max(1.0, float(np.max(np.abs(lam))))  # rounding of rho and the products
        out.append(
            sampled_or_verified(
                "lambda_i > (rho - 1)/2 sum_j c_ij",
                "Li2020 eq. (47)",
                f"rho = {rho:.4f}; rhs = {fmt_list((rho - 1.0) / 2.0 * rows)}; lambda = {fmt_list(lam)}; "
                f"margin = {fmt_list(margin)}",
                "margin > 0 with rho (1 - h) >= 1",
                None
                if np.all(margin > 0)
                else "sampled: the margin fails already at the sampled h (the true h is at least "
                "as large); " + GRID,
                (
                    f"; with the verified h <= {h_up:.6g}: margin >= {fmt_list(margin_at(h_up))}",
                    f"verified: margin > {slack:.1e} (rounding) with the verified bound on h; h is "
                    + INTERVAL,
                )
                if h_up is not None and h_up < 1 and np.all(margin_at(h_up) > slack)
                else None,
                "sampled (unproven): arithmetic with the sampled h; h is " + GRID,
            )
        )
    return out


def check(scenario: ComposedScenario, loop: ClosedLoop | None = None) -> list[Condition]:
    """Conditions of Li2020's theorems (Thm 1, Thm 2) or of the SIR-FTC baseline for a composed
    scenario (see the module docstring).

    Parameters
    ----------
    scenario : ComposedScenario
        A scenario whose controller is ``li2020-adaptive`` or ``sir-ftc``; the numbers are read from its
        sections (network adjacency and delays, the law's gains, the horizon and step).
    loop : ClosedLoop, optional
        Its built loop (unused; the signature of
        :func:`~formation_ftc.methods.composed.register_conditions`).

    Returns
    -------
    list of Condition
        Empty when the composition is outside the theorems (``li2020-adaptive`` without a ``graph`` or
        ``delayed-graph`` network).
    """
    law = law_of(scenario)
    if law is None:
        return []
    ctl = scenario.section("controller")
    n = scenario.section("plant").count
    k = per_spacecraft(ctl.k, n, "controller.k")
    k_positive = exact("k_i > 0", "Li2020 Lemma 2", fmt_list(k), "> 0", bool(np.all(k > 0)), VALUES)
    if law == "sir-ftc":
        gains = f"k0 = {ctl.k0}, Phi = {ctl.phi}"
        positive = ctl.k0 > 0 and ctl.phi > 0
        return [
            k_positive,
            exact("SIR-FTC gains positive", "Li2020 Sec. IV-D", gains, "> 0", positive, VALUES),
        ]
    C = np.asarray(scenario.section("network").adjacency, dtype=float)
    thm = "Theorem 1" if law == "thm1" else "Theorem 2"
    br, sc = balance_report(C, tol=1e-12), is_strongly_connected(C)
    d0 = per_spacecraft(ctl.d_hat0, n, "controller.d_hat0")
    sigma_a = per_spacecraft(ctl.sigma_a, n, "controller.sigma_a")
    sign = -1 if (ctl.dhat_sign_literal and law == "thm2") else 1  # as the catalog builds the law
    out = [
        exact(
            "communication graph balanced",
            f"Li2020 {thm}, Sec. II-C; E000-07",
            str(br),
            "row sums = column sums",
            br.balanced,
            "exact: row/column sums (tolerance 1e-12)"
            + (
                ""
                if br.balanced
                else "; the theorems assume a balanced graph; the printed C is not balanced (the "
                "closed loop still converges in simulation)"
            ),
        ),
        exact(
            "communication graph strongly connected",
            "Li2020 Sec. IV-A, Fig. 3",
            str(sc),
            "True",
            sc,
            "exact: reachability on the adjacency pattern",
            required=False,
        ),
        k_positive,
        exact(
            "d_hat_i(0) > 0", "Li2020 eq. (27)", fmt_list(d0), "> 0", bool(np.all(d0 > 0)), VALUES
        ),
        exact(
            "sigma_i integrable",
            "Li2020 eq. (11), (13)-(16)",
            f"{ctl.sigma_form}, a = {fmt_list(sigma_a)}",
            "int_0^inf sigma < inf",
            True,
            "exact: closed-form integrals: exp(-a t): 1/a; 1/(a (t+t0)^2): 1/(a t0)",
        ),
        exact(
            "sign of d_hat tanh term",
            "Li2020 eq. (24)/(42); E000-04",
            f"{sign:+d}",
            "+1 (proof steps (34)-(36))",
            sign > 0,
            "exact: sign chosen by the scenario",
        ),
    ]
    if law == "thm2":
        out += _delay_conditions(scenario, C, per_spacecraft(ctl.lam, n, "controller.lam"))
    x_star, r_star = lemma3_constant()
    out.append(
        informative(
            "Lemma 3 constant r*",
            "Li2020 eq. (22)",
            f"x* = {x_star:.6f}, r* = {r_star:.6f}",
            "informative",
            True,
            "informative: root of e^{-2x} + 1 - 2x = 0 (brentq, xtol 1e-15)",
        )
    )
    return out
