"""Seeds where they matter: run a league in blocks of seeds until its ranking is resolved.

After each block the ranking of every level is recomputed on all the seeds so far
(:func:`formation_ftc.league.report.ranking` with its confidence): every adjacent pair of methods is

* **separated** when the exact McNemar test on their paired pass/fail separates their pass rates
  (Holm-adjusted p < alpha, :func:`~formation_ftc.league.statistics.paired_comparison`);
* otherwise, when that test on as many pairs would have separated pass rates that differ by the
  stated ``margin`` with at least the stated ``power`` (:func:`~formation_ftc.league.statistics.mcnemar_power`
  at alpha / m, m the level's comparisons: the strictest step of Holm's procedure, so the power is a
  lower bound): **separated** on the requirement metric when the pass rates are equal and the
  Wilcoxon test on the metric separates them, else **tied**;
* **open** otherwise: more seeds could still tell. A metric separation with too few pairs to bound
  the pass-rate difference stays open: the ranking's first key is the pass rate.

The league stops when no pair is open ("resolved") or when the next block would pass ``max_seeds``
("budget"). Block k holds the seeds ``k * block .. (k + 1) * block - 1``, the same replicates as a league
of that many seeds (:func:`~formation_ftc.league.runner.run_league` with ``first_seed``), so the verdict
at n seeds is the verdict of the fixed league of n seeds. ``DIR/resolution.json`` records every block's
verdicts, why it stopped, and the runs it used against the league's fixed seed count.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

from formation_ftc.atomic import atomic_write
from formation_ftc.league.definition import LeagueError, LeagueSpec, load_league

__all__ = ["RESOLUTION_FILE", "pair_verdicts", "run_until_resolved"]

#: the record of a league run until resolved, in its directory
RESOLUTION_FILE = "resolution.json"


def pair_verdicts(
    rank: dict[str, list[dict[str, Any]]], margin: float, power: float
) -> dict[str, list[dict[str, Any]]]:
    """The verdict on every adjacent pair of every level of a ranking with confidence.

    Parameters
    ----------
    rank : dict
        Level -> ranking rows (:func:`formation_ftc.league.report.ranking` with ``runs``: each row
        but the first has ``p_adjusted``, ``separated``, ``only_above_passed``, ``only_this_passed``,
        and every row ``runs``).
    margin : float
        Pass-rate difference a tie must exclude, in (0, 1] [-].
    power : float
        Power at which a pair not separated is a tie, in (0, 1) [-].

    Returns
    -------
    dict
        Level -> one dict per adjacent pair: ``above``, ``below`` (method names), ``verdict``
        ("separated", "tied" or "open"), ``p_adjusted``, ``pairs``, ``discordant`` (fraction),
        ``power`` (of the McNemar test at ``margin`` on these pairs), ``by`` ("pass rate" or
        "metric" for a separated pair, else None).
    """
    from formation_ftc.league import statistics as st

    out: dict[str, list[dict[str, Any]]] = {}
    for level, rows in rank.items():
        m = max(len(rows) - 1, 1)
        verdicts = []
        for above, this in zip(rows, rows[1:], strict=False):
            pairs = int(min(above["runs"], this["runs"]))
            disc = (int(this["only_above_passed"]) + int(this["only_this_passed"])) / max(pairs, 1)
            pw = st.mcnemar_power(pairs, disc, margin, st.ALPHA / m)
            mcnemar = this["test"] == "mcnemar"  # else Wilcoxon: the pass rates are equal
            if this["separated"] and (mcnemar or pw >= power):
                verdict, by = "separated", "pass rate" if mcnemar else "metric"
            else:
                verdict, by = "open" if pw < power else "tied", None
            verdicts.append(
                {
                    "above": above["method"],
                    "below": this["method"],
                    "verdict": verdict,
                    "p_adjusted": this["p_adjusted"],
                    "pairs": pairs,
                    "discordant": disc,
                    "power": pw,
                    "by": by,
                }
            )
        out[str(level)] = verdicts
    return out


def _check(name: str, value: float, low: float, high: float) -> None:
    if not low < value < high:
        raise LeagueError(f"{name} = {value}: must lie in ({low:g}, {high:g})")


def run_until_resolved(
    league: str | Path | LeagueSpec,
    out_dir: str | Path,
    *,
    block: int | None = None,
    max_seeds: int | None = None,
    margin: float = 0.1,
    power: float = 0.8,
    log: Any = None,
    **run_options: Any,
) -> dict[str, Any]:
    """Run ``league`` into ``out_dir`` in blocks of ``block`` seeds (default: its quick seed count)
    until every adjacent pair of its rankings is separated or tied, or ``max_seeds`` (default: its
    seed count) would be passed; resumes a directory it wrote (finished blocks are not run again).

    ``run_options`` go to :func:`~formation_ftc.league.runner.run_league` (methods, executor, progress,
    workers, budgets). Returns the record written to ``DIR/resolution.json``: ``stopped``
    ("resolved" or "budget"), ``seeds``, ``runs``, ``fixed_seeds`` and ``fixed_runs`` (the league's
    own seed count and its runs), ``saved_runs``, the settings, and ``blocks`` (per block: ``seeds``,
    ``runs``, ``open`` pairs, ``wall_time`` [s] and the ``verdicts`` of :func:`pair_verdicts`).
    """
    from formation_ftc.league.report import cell_table, ranking
    from formation_ftc.league.runner import load_league_results, run_league

    spec = league if isinstance(league, LeagueSpec) else load_league(league)
    block = int(block if block is not None else spec.league.quick_seeds)
    max_seeds = int(max_seeds if max_seeds is not None else spec.league.seeds)
    if block < 1:
        raise LeagueError(f"--block = {block}: at least 1 seed per block")
    if max_seeds < block:
        raise LeagueError(f"--max-seeds = {max_seeds}: at least one block ({block} seeds)")
    _check("--margin", margin, 0.0, 1.0 + 1e-12)
    _check("--power", power, 0.0, 1.0)
    out = Path(out_dir)
    record: dict[str, Any] = {
        "league": spec.league.name,
        "block": block,
        "max_seeds": max_seeds,
        "margin": margin,
        "power": power,
        "fixed_seeds": spec.league.seeds,
        "blocks": [],
    }
    t0 = time.perf_counter()
    for first in range(0, max_seeds - block + 1, block):  # every block that fits in max_seeds
        tb = time.perf_counter()
        outcome = run_league(spec, out, seeds=block, first_seed=first, log=log, **run_options)
        meta, runs = load_league_results(out)
        seeds = first + block
        runs = runs[runs["replicate"] < seeds]  # a resumed directory may hold later blocks
        verdicts = pair_verdicts(ranking(meta, cell_table(meta, runs), runs), margin, power)
        n_open = sum(v["verdict"] == "open" for vs in verdicts.values() for v in vs)
        record["blocks"].append(
            {
                "seeds": seeds,
                "runs": int(len(runs)),
                "open": n_open,
                "wall_time": time.perf_counter() - tb,
                "new_runs": outcome.n_runs,
                "verdicts": verdicts,
            }
        )
        if log is not None:
            log(f"{seeds} seeds: {n_open} adjacent pair(s) open")
        if n_open == 0:
            break
    fixed_runs = int(round(len(runs) / seeds * spec.league.seeds))
    record.update(
        stopped="budget" if n_open else "resolved",  # budget: the next block would pass max_seeds
        seeds=seeds,
        runs=int(len(runs)),
        fixed_runs=fixed_runs,
        saved_runs=fixed_runs - int(len(runs)),
        wall_time=time.perf_counter() - t0,
        units={"wall_time": "s", "margin": "1", "power": "1"},
    )
    atomic_write(out / RESOLUTION_FILE, json.dumps(record, indent=1))
    return record
