"""Reproduction ``li2020``: runs li2020-thm1, li2020-thm2-delays, li2020-sirftc (and the balanced-graph
variant and the E000-04 literal-sign run), writes Figs. 4-12 and compares with the paper's claims and
with reference values the paper does not print (docs/references.md; each is recomputed by the
independent numpy loop of benchmarks/li2020_reference.py). The study is declared in ``study.toml``;
:func:`quantities` computes the numbers it reads.
"""

from __future__ import annotations

import numpy as np

from formation_ftc.papers._study import Run, read_study, study
from formation_ftc.report.profile import phase

__all__ = [
    "REPRODUCTION",
    "REFERENCE_RUN",
    "MU1_INITIAL",
    "SUMMARY_KEYS",
    "SCENARIOS",
    "adaptive_drift",
    "quantities",
]

SUMMARY_KEYS = (
    "mu1_final",
    "mu2_final",
    "mu1_max_last_10pct",
    "settle_time_mu1_1m",
    "delta_v_total",
)
_CONSTANTS = read_study("li2020")["reproduction"]["constants"]
#: reference run (not printed in the paper; docs/references.md): scenario -> {metric: value} [m]
REFERENCE_RUN: dict[str, dict[str, float]] = _CONSTANTS["reference_run"]
#: mu1(0) [m] from the printed initial positions and the desired formation at t = 0 (docs/references.md)
MU1_INITIAL: float = _CONSTANTS["mu1_initial"]
SCENARIOS = ["li2020-thm1", "li2020-thm2-delays", "li2020-sirftc", "li2020-thm2-balanced"]


def adaptive_drift(metrics: dict[str, float], names=("m_hat", "beta_hat", "d_hat")) -> dict:
    """Max over spacecraft of |x(T) - x(0.9 T)| / |x(T)| for each adaptive parameter [-], from the run's
    in-run metrics ``<name>_final_sc<i>`` (the horizon) and ``<name>_at_90pct_sc<i>`` (0.9 T)."""
    out = {}
    for n in names:
        sc = sorted(k[len(n) + 9 :] for k in metrics if k.startswith(f"{n}_final_sc"))
        if sc:
            fin = np.array([metrics[f"{n}_final_sc{i}"] for i in sc])
            at90 = np.array([metrics[f"{n}_at_90pct_sc{i}"] for i in sc])
            out[n] = float(np.max(np.abs(fin - at90) / np.maximum(np.abs(fin), 1e-300)))
    return out


def quantities(runs: dict[str, Run], constants: dict) -> dict:
    """The numbers ``study.toml`` reads."""
    from formation_ftc.api import load_scenario
    from formation_ftc.core.graph import balance_report
    from formation_ftc.papers.li2020.conditions import check
    from formation_ftc.papers.programs import simulate

    m = {name: r.metrics for name, r in runs.items()}
    m1, m2, ms = m["li2020-thm1"], m["li2020-thm2-delays"], m["li2020-sirftc"]
    horizon = float(runs["li2020-thm1"].scenario.simulation.horizon)
    m_cor = m2
    if "mu1_max_50_300s" not in m2:  # shortened study: corrected-sign run over the same window
        with phase("run"):
            m_cor = simulate(load_scenario(SCENARIOS[1], {"simulation.horizon": 300.0}))[1]
    adjacency = np.asarray(runs["li2020-thm1"].scenario.section("network").adjacency, dtype=float)
    drift = {n: adaptive_drift(m[n]) for n in SCENARIOS[:2]}
    note = "" if horizon >= 3000 else f"shortened horizon {horizon:g} s"
    q = dict(m1=m1, m2=m2, ms=ms, sir_mu1_final=ms["mu1_final"], thm1_x5=5 * m1["mu1_final"])
    q |= dict(thm1_settle=m1["settle_time_mu1_1m"], mu10=float(runs[SCENARIOS[0]].dataset.mu1[0]))
    q["sir_settle"] = ms["settle_time_mu1_1m"] if np.isfinite(ms["settle_time_mu1_1m"]) else np.inf
    q |= dict(literal_max=m["li2020-thm2-literal-sign"]["mu1_max_50_300s"])
    q |= dict(corrected_max=m_cor["mu1_max_50_300s"], corrected_x10=10 * m_cor["mu1_max_50_300s"])
    q |= dict(balanced=balance_report(adjacency, tol=1e-12).balanced, m_bal=m[SCENARIOS[3]])
    q["convergence"] = [
        {**m[n], "name": n, "fig": fig, "mu1_limit": 0.1 * m[n].get("mu1_at_10s", np.inf)}
        | {"horizon_note": note}
        for n, fig in ((SCENARIOS[0], "4, 6"), (SCENARIOS[1], "8, 10"))
    ]
    q["drift"] = [
        {"name": n, "fig": fig, "clauses": tuple(("<", v, 0.05) for v in drift[n].values())}
        | {"changes": ", ".join(f"{k} {v:.2%}" for k, v in drift[n].items())}
        for n, fig in ((SCENARIOS[0], "7"), (SCENARIOS[1], "11"))
    ]
    q["references"] = [
        {"name": n, "key": k, "value": m[n][k], "reference_value": v, "rel": abs(m[n][k] - v) / v}
        for n, ref in REFERENCE_RUN.items()
        for k, v in ref.items()
        if k in m[n]
    ]
    q["seeds"] = [int(r.scenario.simulation.seed) for r in runs.values()]
    q["checks"] = check(runs[SCENARIOS[0]].scenario) + check(runs[SCENARIOS[1]].scenario)
    summary = {n: {**{k: m[n][k] for k in SUMMARY_KEYS}, **_mu1_samples(m[n])} for n in SCENARIOS}
    return summary | q


def _mu1_samples(metrics: dict) -> dict:
    return {k: v for k, v in metrics.items() if k.startswith("mu1_at_") or k == "mu1_max_after_50s"}


REPRODUCTION = study("li2020", quantities)
