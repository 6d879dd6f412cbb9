"""A league run until its ranking is resolved: the exact McNemar power against a Monte Carlo estimate
of the statsmodels test, the pair verdicts on constructed rankings, and a tiny league run in blocks
of seeds (the blocks are the replicates of a league of that many seeds; resume; refusals)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from formation_ftc.cli import main
from formation_ftc.league.definition import LeagueError, load_league
from formation_ftc.league.resolution import pair_verdicts, run_until_resolved
from formation_ftc.league.runner import _campaign, run_league
from formation_ftc.league.statistics import mcnemar_power


@pytest.mark.parametrize(
    ("pairs", "discordant", "difference", "alpha"),
    [(60, 0.2, 0.1, 0.05), (200, 0.3, 0.1, 0.025), (40, 0.05, 0.1, 0.05)],
)
def test_mcnemar_power_matches_a_monte_carlo_of_the_statsmodels_test(
    pairs, discordant, difference, alpha
):
    """Draw paired tables with the stated discordance and difference, count how often statsmodels'
    exact McNemar test rejects. 3,000 draws: the estimate's standard error is below 0.0092, so 4.5
    standard errors is 0.042."""
    from statsmodels.stats.contingency_tables import mcnemar

    rng = np.random.default_rng(5)
    psi = max(discordant, difference)
    p = [(psi + difference) / 2, (psi - difference) / 2, 1 - psi]
    draws = rng.multinomial(pairs, p, size=3000)
    hits = 0
    for b, c, same in draws:
        if b + c and mcnemar([[same, b], [c, 0]], exact=True).pvalue <= alpha:
            hits += 1
    assert mcnemar_power(pairs, discordant, difference, alpha) == pytest.approx(
        hits / len(draws), abs=0.042
    )


def test_more_pairs_more_power_and_bad_input():
    powers = [mcnemar_power(n, 0.2, 0.1, 0.05) for n in (20, 100, 400, 1600)]
    assert powers == sorted(powers) and powers[0] < 0.3 and powers[-1] > 0.99
    assert mcnemar_power(0, 0.2, 0.1, 0.05) == 0.0
    with pytest.raises(ValueError, match="difference"):
        mcnemar_power(10, 0.2, 0.0, 0.05)


def _row(method, runs, separated=None, above=0, this=0, p=None, test="mcnemar"):
    return {
        "method": method,
        "test": test,
        "runs": runs,
        "separated": separated,
        "only_above_passed": above,
        "only_this_passed": this,
        "p_adjusted": p,
    }


def test_pair_verdicts_separated_tied_open():
    rank = {
        "big": [
            _row("a", 700),
            _row("b", 700, True, 40, 5, 1e-6),  # separated
            _row("c", 700, False, 3, 2, 1.0),  # few discordant pairs on 700: would see 0.1
            _row("d", 700, True, 2, 2, 1e-4, "wilcoxon"),  # equal pass rates, metric separates
        ],
        "small": [
            _row("a", 14),
            _row("b", 14, False, 2, 1, 1.0),  # 14 pairs: cannot tell
            _row("c", 14, True, 1, 1, 1e-3, "wilcoxon"),  # the metric, but pass rates not bounded
        ],
    }
    v = pair_verdicts(rank, margin=0.1, power=0.8)
    assert [x["verdict"] for x in v["big"]] == ["separated", "tied", "separated"]
    assert [x["by"] for x in v["big"]] == ["pass rate", None, "metric"]
    assert [x["verdict"] for x in v["small"]] == ["open", "open"]
    assert v["big"][1]["power"] > 0.99 and v["big"][1]["pairs"] == 700
    assert v["small"][0]["power"] < 0.8
    assert v["small"][0]["discordant"] == pytest.approx(3 / 14)


def test_tiny_league_until_resolved_in_blocks(tmp_path, tiny_league):
    path = tiny_league(tmp_path, methods=("sir-ftc", "lqr"))
    out = tmp_path / "out"
    rec = run_until_resolved(path, out, block=2, max_seeds=4, margin=0.5, power=0.5)
    meta = json.loads((out / "league.json").read_text())
    assert meta["blocks"][0] == [0, 2] and meta["seeds"] == rec["seeds"]
    assert rec["stopped"] in ("resolved", "budget") and rec["seeds"] in (2, 4)
    last = rec["blocks"][-1]
    n_open = sum(v["verdict"] == "open" for vs in last["verdicts"].values() for v in vs)
    assert (n_open == 0) == (rec["stopped"] == "resolved") and last["open"] == n_open
    if rec["stopped"] == "budget":
        assert rec["seeds"] == 4
    n_cells = rec["runs"] // rec["seeds"]
    assert (
        rec["fixed_runs"] == n_cells * 100 and rec["saved_runs"] == rec["fixed_runs"] - rec["runs"]
    )
    # resumed: nothing new is run, the same record comes back
    again = run_until_resolved(path, out, block=2, max_seeds=4, margin=0.5, power=0.5)
    assert again["blocks"][-1]["verdicts"] == last["verdicts"] and again["runs"] == rec["runs"]
    # a plain run into a directory run in blocks is refused, naming the way to resume it
    with pytest.raises(LeagueError, match="until-resolved"):
        run_league(path, out, seeds=rec["seeds"])
    # the leaderboard of every block, with the record under the Markdown board
    assert main(["-q", "league", "report", str(out), "--no-plots"]) == 0
    md = (out / "leaderboard" / "leaderboard.md").read_text()
    assert f"until resolved: stopped at {rec['seeds']} seeds per cell" in md
    runs = pd.read_parquet(out / "leaderboard" / "runs.parquet")
    assert sorted(set(runs["replicate"])) == list(range(rec["seeds"]))


def test_a_later_block_holds_the_replicates_of_a_longer_league(tmp_path, tiny_league):
    """Blocks of seeds 0-1 and 2-3 add up to the runs of a 4-seed league: the same seeds and drawn
    inputs per replicate (so the same numbers: a run is a function of its inputs)."""
    from formation_ftc.campaign import make_plan
    from formation_ftc.league.runner import load_league_results

    path = tiny_league(tmp_path, methods=("lqr",))
    out = tmp_path / "blocks"
    run_league(path, out, seeds=2, first_seed=0)
    with pytest.raises(LeagueError, match="another --out"):
        run_league(path, out, seeds=2, first_seed=4)  # a gap: seeds 2-3 missing
    run_league(path, out, seeds=2, first_seed=2)
    meta, runs = load_league_results(out)
    assert meta["blocks"] == [[0, 2], [2, 2]] and meta["seeds"] == 4
    assert (out / "lqr" / "campaign-from-000002").is_dir()
    files = sorted((out / "lqr" / "cells").glob("*.toml"))
    whole = make_plan(_campaign(load_league(path), "lqr", files, 4, []))
    assert sorted(set(runs["replicate"])) == [0, 1, 2, 3]
    for _, r in runs.iterrows():
        g = whole.base_names.index(str(r["scenario"]))
        want = whole.run_inputs(g * 4 + int(r["replicate"]))
        assert int(r["seed"]) == want.seed
        assert r["input:actuator.onset"] == want.values["actuator.onset"]


def test_until_resolved_options_are_checked(tmp_path, tiny_league):
    path = str(tiny_league(tmp_path))
    out = str(tmp_path / "o")
    assert main(["-q", "league", "run", path, "--out", out, "--block", "2"]) == 2
    assert main(["-q", "league", "run", path, "--out", out, "--until-resolved", "--quick"]) == 2
    for bad in (
        ["--power", "1.5"],
        ["--margin", "0"],
        ["--block", "0"],
        ["--max-seeds", "1", "--block", "2"],
    ):
        assert main(["-q", "league", "run", path, "--out", out, "--until-resolved", *bad]) == 2, bad
    assert not (tmp_path / "o").exists()
