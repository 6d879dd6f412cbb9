"""``formation-ftc league {list, run, report}``; each takes ``--json`` (one JSON document on stdout at
the end, progress and log lines on stderr; schemas in docs/cli.md)."""

from __future__ import annotations

import argparse
import functools
import sys
import time
from pathlib import Path
from typing import Any

from formation_ftc.cli_options import add_budget_options, add_executor_options
from formation_ftc.exitcodes import add_json_option, print_json

__all__ = ["add_cli"]


def _cmd_list(args) -> int:
    from formation_ftc.league.definition import builtin_leagues, load_league

    rows: list[dict[str, Any]] = []
    for name in builtin_leagues():
        spec = load_league(name)
        meta = spec.league
        # in the file's order; the requirement: metric, max, units, stl, verdict
        listed = {"battery", "seeds", "quick_seeds", "horizon", "requirement"}
        rows.append(
            {
                "name": name,
                "description": meta.description,
                "kind": meta.kind,
                "methods": [m.name for m in spec.methods],
                "levels": [lv.name for lv in spec.levels],
                **meta.model_dump(include=listed),
                "units": {"horizon": "s"},
            }
        )
    if args.json:
        print_json({"leagues": rows})
        return 0
    for r in rows:
        print(f"{r['name']}  {r['description']}")
        print(
            f"    methods: {', '.join(r['methods'])}; battery {r['battery']}; {r['seeds']} seeds "
            f"per cell ({r['quick_seeds']} with --quick)"
        )
    return 0


def _quiet(args) -> bool:
    """``-q``: no progress and no informational lines (results and errors only)."""
    return int(getattr(args, "verbosity", 0) or 0) < 0


def _log(args):
    """The stderr log of a command (None with ``-q``; cli.main makes stderr lossy)."""
    return None if _quiet(args) else lambda line: print(line, file=sys.stderr, flush=True)


def _cmd_run(args) -> int:
    from formation_ftc.campaign.executors import cap_workers, make_executor
    from formation_ftc.league.definition import LeagueError, load_league
    from formation_ftc.league.runner import METHOD_WORKER_BYTES, run_league
    from formation_ftc.limits import Budgets
    from formation_ftc.sim.runtime import schedulable_cpus

    t0 = time.perf_counter()
    if not str(args.out).strip():
        raise LeagueError("--out: empty path; give the league directory, e.g. --out out/league")
    budgets = Budgets.resolve(args.max_memory, args.max_run_steps, args.max_campaign_steps)
    distributed = bool(args.scheduler or args.dask_local)
    dask = dict(scheduler=args.scheduler, dask_local=args.dask_local) if distributed else {}
    factory = functools.partial(make_executor, workers=args.workers if distributed else 1, **dask)
    if distributed:
        factory()  # checked now
    if args.workers is not None and args.workers < 1:
        raise LeagueError(f"--workers must be >= 1, got {args.workers}")
    methods = [m.strip() for m in args.methods.split(",")] if args.methods else None
    # locally: one process per method, as many side by side as --workers (default: the CPU cores), at
    # most as many as the cores and the available memory hold
    parallel = 1
    if not distributed:
        n_methods = len(methods) if methods else len(load_league(args.league).methods)
        what = "--workers" if args.workers else "--workers (default: one per CPU core)"
        parallel = cap_workers(
            min(args.workers or schedulable_cpus(), n_methods),
            per_worker_bytes=METHOD_WORKER_BYTES,
            what=what,
        )

    options = {
        "methods": methods,
        "executor_factory": factory,
        "progress": not (args.no_progress or _quiet(args)),
        "log": _log(args),
        "parallel_methods": parallel,
        "budgets": budgets,
    }
    if args.until_resolved:
        return _until_resolved(args, options, t0)
    for flag in ("block", "max_seeds", "margin", "power"):
        if getattr(args, flag) is not None:
            raise LeagueError(f"--{flag.replace('_', '-')}: only with --until-resolved")
    outcome = run_league(args.league, args.out, seeds=args.seeds, quick=args.quick, **options)
    methods = [{"name": m, "wall_time": s} for m, s in outcome.per_method.items()]  # as finished
    return _finish(
        args,
        t0,
        {"runs": outcome.n_runs, "failed": outcome.n_failed, "methods": methods},
        lambda wall: (
            f"league done: {outcome.n_runs} runs ({outcome.n_failed} failed or diverged) "
            f"in {outcome.out_dir}, {wall:.1f} s"
        ),
    )


def _finish(args, t0: float, extra: dict, text, outputs: dict | None = None) -> int:
    """Write the leaderboard of a league run, then print its ``--json`` document (the board, ``extra``,
    the wall time; ``outputs``: more files) or ``text(wall time)`` and the board."""
    from formation_ftc.league.report import write_leaderboard

    board = write_leaderboard(args.out, plots=not args.no_plots)
    wall = time.perf_counter() - t0
    if args.json:
        doc = _board_doc(args.out, board)
        doc["outputs"].update(outputs or {})
        units = {**doc["units"], "wall_time": "s"}
        print_json({"league": board["league"], **doc, **extra, "wall_time": wall, "units": units})
        return 0
    print(text(wall))
    _print_board(board, args.out)
    return 0


def _until_resolved(args, options: dict, t0: float) -> int:
    """``league run --until-resolved``: blocks of seeds until the ranking is resolved (or the budget
    is spent), then the leaderboard of every seed run."""
    from formation_ftc.league.definition import LeagueError
    from formation_ftc.league.report import resolution_text
    from formation_ftc.league.resolution import RESOLUTION_FILE, run_until_resolved

    if args.seeds is not None or args.quick:
        raise LeagueError(
            "--until-resolved: the seeds come in blocks (--block, --max-seeds); leave out "
            "--seeds and --quick"
        )
    record = run_until_resolved(
        args.league,
        args.out,
        block=args.block,
        max_seeds=args.max_seeds,
        margin=0.1 if args.margin is None else args.margin,
        power=0.8 if args.power is None else args.power,
        **options,
    )
    resolution = {"resolution": str(Path(args.out) / RESOLUTION_FILE)}
    return _finish(args, t0, {"resolution": record}, lambda _: resolution_text(record), resolution)


def _print_board(board, directory) -> None:
    """The ranking of every level, then the files written under ``directory``; an incomplete league
    says what is missing first."""
    from formation_ftc.league.report import _display_rows, incomplete_note, seeds_text

    comp = board.get("completeness")
    note = incomplete_note(comp) if comp else None
    if note:
        print(note)
    if comp:
        print(f"{board['league']}: {seeds_text(comp)}")
    metric = board["requirement"]["metric"]
    for level, rows in board["ranking"].items():
        print(f"\n{level}: rank  method  pass-rate [95 % CI]  median {metric} [95 % CI]")
        for r in _display_rows(rows, metric):
            print(
                f"  {r['rank_text']:>3}  {r['method']:<16} {r['pass_rate_text']:<20} "
                f"{r['median_text']}"
            )
    if board.get("ranking_method"):
        print(f"\n{board['ranking_method']}")
    print(
        f"wrote {directory}/leaderboard/index.html, leaderboard.json, leaderboard.md, "
        "cells.parquet, runs.parquet and ranking.parquet"
    )


def _board_doc(directory, board) -> dict:
    """The ``--json`` document of ``league report`` (and the leaderboard part of ``league run``'s)."""
    from formation_ftc.parquet_units import read_units

    out = Path(directory) / "leaderboard"
    return {
        "dir": str(directory),
        "leaderboard": board,
        "units": read_units(out / "cells.parquet"),  # of the cells' (and ranking rows') columns
        "outputs": {
            "league_json": str(Path(directory) / "league.json"),
            "index": str(out / "index.html"),
            "leaderboard_json": str(out / "leaderboard.json"),
            "leaderboard_md": str(out / "leaderboard.md"),
            "cells": str(out / "cells.parquet"),
            "runs": str(out / "runs.parquet"),
            "ranking": str(out / "ranking.parquet"),
        },
    }


def _cmd_report(args) -> int:
    from formation_ftc.league.report import incomplete_note, write_leaderboard

    board = write_leaderboard(args.dir, plots=not args.no_plots, tuned=args.tuned)
    if args.json:
        note = incomplete_note(board["completeness"])
        if note and not _quiet(args):
            print(f"warning: {note}", file=sys.stderr)
        print_json(_board_doc(args.dir, board))
        return 0
    _print_board(board, args.dir)
    return 0


#: the arguments of ``league run`` before the executor and budget options: name or flag -> the keywords
#: of ``add_argument``
_RUN_OPTIONS: dict[str, dict[str, Any]] = {
    "league": dict(metavar="NAME_OR_FILE", help="built-in league name or league TOML file"),
    "--out": dict(required=True, help="league directory (resumed when it holds this league)"),
    "--seeds": dict(type=int, help="Monte Carlo seeds per cell (overrides the file)"),
    "--quick": dict(action="store_true", help="the league's quick seed count (e.g. 10 per cell)"),
    "--methods": dict(help="comma-separated subset of the league's methods"),
    "--until-resolved": dict(
        action="store_true",
        help="run blocks of seeds until every adjacent pair of the ranking is separated or tied "
        "(writes DIR/resolution.json)",
    ),
    "--block": dict(type=int, help="seeds per block (default: the quick seed count)"),
    "--max-seeds": dict(
        type=int,
        help="most seeds per cell with --until-resolved (default: the league's seed count)",
    ),
    "--margin": dict(type=float, help="pass-rate difference a tie excludes (default 0.1)"),
    "--power": dict(type=float, help="power at which a pair not separated is a tie (default 0.8)"),
}


def add_cli(subparsers) -> argparse.ArgumentParser:
    """Add the ``league`` command (``list``, ``run``, ``report``) to ``subparsers``."""
    p = subparsers.add_parser(
        "league", help="FTC league: every method on one realistic formation, same faults"
    )
    sub = p.add_subparsers(dest="league_command", required=True)
    q = sub.add_parser("list", help="list the built-in leagues")
    add_json_option(q)
    q.set_defaults(func=_cmd_list)
    q = sub.add_parser("run", help="run or resume a league and write its leaderboard")
    for flag, keywords in _RUN_OPTIONS.items():
        q.add_argument(flag, **keywords)
    add_executor_options(
        q,
        workers="methods run side by side, one process each (default: one per CPU core; at most one "
        "per core and per 1.2 GB of available memory; 1: in-process)",
    )
    add_budget_options(
        q, batch="one batch of a method's runs", whole="the whole league, all methods together"
    )
    q.add_argument(
        "--no-progress",
        action="store_true",
        help="no progress bars (one line per step check and per method; -q: none)",
    )
    q.add_argument("--no-plots", action="store_true", help="leaderboard without figures")
    add_json_option(q)
    q.set_defaults(func=_cmd_run)
    q = sub.add_parser("report", help="(re)write the leaderboard of a league directory")
    q.add_argument("dir", metavar="DIR", help="league directory")
    q.add_argument("--no-plots", action="store_true", help="leaderboard without figures")
    q.add_argument(
        "--tuned",
        metavar="TUNED_DIR",
        help="directory of `formation-ftc tune` results for the ranking's tuned column "
        "(default: DIR/tuned when it exists)",
    )
    add_json_option(q)
    q.set_defaults(func=_cmd_report)
    return p
