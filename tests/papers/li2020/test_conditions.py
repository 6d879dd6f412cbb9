"""Li2020 condition checks of composed scenarios and bad-input rejection (SPEC P0.6-1/2/3, issue 3
"Bad input")."""

from __future__ import annotations

import math

import numpy as np
import pytest

from formation_ftc.api import check as api_check
from formation_ftc.config.loader import ScenarioError
from formation_ftc.core.graph import balance_report, is_strongly_connected
from formation_ftc.methods.composed import make_loop
from formation_ftc.papers.li2020.conditions import check, delay_stats, lemma3_constant

C_PRINTED = [[0, 0, 0.5, 0], [0.6, 0, 0, 0], [0, 0.5, 0, 0.4], [0.6, 0, 0, 0]]
C_BAL = [[0, 0, 0.9, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0.4], [0.4, 0, 0, 0]]


def _by_name(conds):
    return {c.name: c for c in conds}


def test_printed_graph_not_balanced_with_sums(load):
    """P0.6-1: row sums [0.5,0.6,0.9,0.6], column sums [1.2,0.5,0.5,0.4] (exact) -> not balanced."""
    br = balance_report(C_PRINTED)
    assert not br.balanced
    assert np.allclose(br.row_sums, [0.5, 0.6, 0.9, 0.6], atol=1e-15)
    assert np.allclose(br.column_sums, [1.2, 0.5, 0.5, 0.4], atol=1e-15)
    assert balance_report(C_BAL).balanced
    assert is_strongly_connected(C_PRINTED) and is_strongly_connected(C_BAL)
    c = _by_name(check(load("li2020-thm1")))["communication graph balanced"]
    assert c.holds is False and c.required
    assert (
        "NOT balanced" in c.value
        and "0.5, 0.6, 0.9, 0.6" in c.value
        and "1.2, 0.5, 0.5, 0.4" in c.value
    )
    cb = _by_name(check(load("li2020-thm2-balanced")))["communication graph balanced"]
    assert cb.holds is True


def test_delay_rate_bound_and_lambda_condition(load):
    """P0.6-2: max dT/dt over used edges = 0.120 (T34) +- 1e-3; rho = 1/(1 - 0.12); lambda margin > 0
    with largest rhs 0.0614; all 12 printed delays have rate < 1 (max 0.44, T12)."""
    scn = load("li2020-thm2-delays")
    stats = {st.name: st for st in delay_stats(scn)}
    used = ["T13", "T21", "T32", "T34", "T41"]
    worst = max(used, key=lambda n: stats[n].rate_max)
    assert worst == "T34" and abs(stats["T34"].rate_max - 0.12) < 1e-3
    assert abs(max(s.rate_max for s in stats.values()) - 0.44) < 5e-3
    assert max(stats, key=lambda n: stats[n].rate_max) == "T12"
    conds = _by_name(check(scn))
    assert conds["delay rate bound (used edges)"].holds
    assert "T34" in conds["delay rate bound (used edges)"].value
    lam = conds["lambda_i > (rho - 1)/2 sum_j c_ij"]
    assert lam.holds and "rho = 1.136" in lam.value
    rho = 1 / (1 - stats["T34"].rate_max)
    rhs = (rho - 1) / 2 * np.sum(C_PRINTED, axis=1)
    assert abs(rhs.max() - 0.0614) < 5e-4
    assert conds["sign of d_hat tanh term"].holds


def test_lemma3_constant():
    """P0.6-3: r* = 0.278465 +- 1e-6 with x* = 0.639232."""
    x, r = lemma3_constant()
    assert abs(math.exp(-2 * x) + 1 - 2 * x) < 1e-14
    assert abs(x - 0.639232) < 1e-6 and abs(r - 0.278465) < 1e-6


def _delays_with(entry, value):
    base = [["0"] * 4 for _ in range(4)]
    for i, j, v in [
        (0, 2, "1 - 0.2*cos(0.4*t)"),
        (1, 0, "1 + 0.2*sin(0.2*t)"),
        (2, 1, "2 + 0.4*sin(0.2*t)"),
        (2, 3, "3 + 0.6*sin(0.2*t)"),
        (3, 0, "1 + 0.2*cos(0.2*t)"),
    ]:
        base[i][j] = v
    base[entry[0]][entry[1]] = value
    return base


def test_rejected_on_negative_delay_or_beyond_the_history(load):
    """A used delay must stay in [0, max_delay] at every step (the history holds max_delay seconds)."""
    for entry, expr, words in (
        ((2, 3), "0.5 - 0.01*t", ["negative", "T34", "link 4 -> 3", "goes negative at t = 50"]),
        ((2, 3), "3.5 + 0.2*sin(0.2*t)", ["T34", "3.7", "exceeds network.max_delay = 3.6"]),
    ):
        with pytest.raises(ScenarioError) as exc:
            load(
                "li2020-thm2-delays",
                {"network.delays": _delays_with(entry, expr), "simulation.horizon": 100.0},
            )
        for w in words:
            assert w in str(exc.value), str(exc.value)
    # an unused link may carry any delay: it is not read (the non-negativity condition states it)
    scn = load(
        "li2020-thm2-delays",
        {"network.delays": _delays_with((0, 1), "-1"), "simulation.horizon": 100.0},
    )
    assert _by_name(check(scn))["delays non-negative"].holds is False


def test_rate_of_one_fails_the_theorem_condition(load):
    """dT/dt >= 1 on a used link (eq. (46)) is outside Thm 2: the condition fails (the loop still runs)."""
    scn = load(
        "li2020-thm2-delays",
        {"network.delays": _delays_with((0, 2), "1 + 0.2*sin(5*t)"), "simulation.horizon": 100.0},
    )
    rate = _by_name(check(scn))["delay rate bound (used edges)"]
    assert rate.holds is False and "T13" in rate.value and rate.required


def test_delays_shorter_than_the_step_read_the_message_sent_now(load):
    """T >= dt on every used link: the reads never need the message sent within the step (the built-in
    scenarios); a shorter delay switches on the blend with it (DelayedGraphNetwork.short_delays)."""
    assert make_loop(load("li2020-thm2-delays")).network.short_delays is False
    short = load(
        "li2020-thm2-delays",
        {"network.delays": _delays_with((1, 0), "0.005"), "simulation.horizon": 100.0},
    )
    assert make_loop(short).network.short_delays is True


def test_conditions_apply_to_the_li2020_laws_only(load):
    """Registered on the controller types: the law over a graph / delayed graph states the theorem's
    conditions, SIR-FTC its own, a law over a graph that loses links none (outside the theorems)."""
    names = {c.name for c in api_check(load("li2020-thm2-delays"))}
    assert {"components fit together", "lambda_i > (rho - 1)/2 sum_j c_ij"} <= names
    sir = {c.name for c in api_check(load("li2020-sirftc"))}
    assert sir == {"components fit together", "k_i > 0", "SIR-FTC gains positive"}
    lossy = load(
        "li2020-thm1",
        {"network.type": "graph-link-loss", "network.lost_links": [[1, 3]], "network.onset": 5.0},
    )
    assert check(lossy) == []


@pytest.mark.parametrize(
    "C, words",
    [
        (
            [[0, 0, -0.5, 0], [0.6, 0, 0, 0], [0, 0.5, 0, 0.4], [0.6, 0, 0, 0]],
            ["adjacency[0][2]", ">= 0"],
        ),
        ([[0.3, 0, 0.5, 0], [0.6, 0, 0, 0], [0, 0.5, 0, 0.4], [0.6, 0, 0, 0]], ["self-loops"]),
        ([[0, 0.5], [0.5, 0]], ["4x4"]),
    ],
)
def test_bad_adjacency_rejected(load, C, words):
    with pytest.raises(ScenarioError) as exc:
        load("li2020-thm1", {"network.adjacency": C})
    for w in words:
        assert w in str(exc.value)


def test_other_validation_messages(load):
    with pytest.raises(ScenarioError, match="controller.k: every value must be finite and > 0"):
        load("li2020-thm1", {"controller.k": -0.2})
    with pytest.raises(ScenarioError, match="network.delays"):
        load("li2020-thm1", {"network.type": "delayed-graph"})
    with pytest.raises(ScenarioError, match="unknown name"):
        load("li2020-thm1", {"plant.disturbance_force": ["0", "0", "x*t"]})
