"""``formation-ftc league {list, run, report}``."""

from __future__ import annotations

import argparse
import os
import sys

from formation_ftc.campaign.cli import add_dask_options

__all__ = ["add_cli"]


def _cmd_list(args) -> int:
    from formation_ftc.league.definition import builtin_leagues, load_league

    for name in builtin_leagues():
        spec = load_league(name)
        methods = ", ".join(m.name for m in spec.methods)
        print(f"{name}  {spec.league.description}")
        print(f"    methods: {methods}; battery {spec.league.battery}; {spec.league.seeds} seeds per cell "
              f"({spec.league.quick_seeds} with --quick)")
    return 0


def _cmd_run(args) -> int:
    from formation_ftc.campaign.executors import make_executor
    from formation_ftc.league.report import write_leaderboard
    from formation_ftc.league.runner import run_league

    if not str(args.out).strip():
        from formation_ftc.league.definition import LeagueError

        raise LeagueError("--out: empty path; give the league directory, e.g. --out out/league")
    distributed = bool(args.scheduler or args.dask_local)
    if distributed:
        make_executor(workers=args.workers, scheduler=args.scheduler, dask_local=args.dask_local)  # checked now
    if args.workers is not None and args.workers < 1:
        from formation_ftc.league.definition import LeagueError

        raise LeagueError(f"--workers must be >= 1, got {args.workers}")
    # locally: one process per method, as many side by side as --workers (default: the CPU cores)
    parallel = 1 if distributed else (args.workers or os.cpu_count() or 1)

    def factory():
        if distributed:
            return make_executor(workers=args.workers, scheduler=args.scheduler, dask_local=args.dask_local)
        return make_executor(workers=1)

    methods = [m.strip() for m in args.methods.split(",")] if args.methods else None
    outcome = run_league(args.league, args.out, seeds=args.seeds, quick=args.quick, methods=methods,
                         executor_factory=factory, progress=not args.no_progress and parallel == 1,
                         log=lambda s: print(s, file=sys.stderr), parallel_methods=parallel)
    print(f"league done: {outcome}")
    board = write_leaderboard(args.out, plots=not args.no_plots)
    _print_ranking(board)
    print(f"wrote {args.out}/leaderboard/index.html, leaderboard.json, cells.parquet and runs.parquet")
    return 0


def _print_ranking(board) -> None:
    metric = board["requirement"]["metric"]
    for level, rows in board["ranking"].items():
        print(f"\n{level}: rank  method  pass-rate  median {metric}")
        for r in rows:
            med = r.get(f"{metric}_median")
            print(f"  {r['rank']:>2}  {r['method']:<16} {r['pass_rate']:6.2f}  "
                  f"{'-' if med is None else format(med, '.3g')}")


def _cmd_report(args) -> int:
    from formation_ftc.league.report import write_leaderboard

    board = write_leaderboard(args.dir, plots=not args.no_plots)
    _print_ranking(board)
    print(f"wrote {args.dir}/leaderboard/index.html, leaderboard.json, cells.parquet and runs.parquet")
    return 0


def add_cli(subparsers) -> argparse.ArgumentParser:
    """Add the ``league`` command (``list``, ``run``, ``report``) to ``subparsers``."""
    p = subparsers.add_parser("league", help="FTC league: every method on one realistic formation, same faults")
    sub = p.add_subparsers(dest="league_command", required=True)
    q = sub.add_parser("list", help="list the built-in leagues")
    q.set_defaults(func=_cmd_list)
    q = sub.add_parser("run", help="run or resume a league and write its leaderboard")
    q.add_argument("league", metavar="NAME_OR_FILE", help="built-in league name or league TOML file")
    q.add_argument("--out", required=True, help="league directory (resumed when it holds this league)")
    q.add_argument("--seeds", type=int, default=None, help="Monte Carlo seeds per cell (overrides the file)")
    q.add_argument("--quick", action="store_true", help="the league's quick seed count (e.g. 10 per cell)")
    q.add_argument("--methods", default=None, help="comma-separated subset of the league's methods")
    q.add_argument("--workers", type=int, default=None,
                   help="methods run side by side, one process each (default: one per CPU core; 1: in-process)")
    add_dask_options(q)
    q.add_argument("--no-progress", action="store_true", help="no progress bar")
    q.add_argument("--no-plots", action="store_true", help="leaderboard without figures")
    q.set_defaults(func=_cmd_run)
    q = sub.add_parser("report", help="(re)write the leaderboard of a league directory")
    q.add_argument("dir", metavar="DIR", help="league directory")
    q.add_argument("--no-plots", action="store_true", help="leaderboard without figures")
    q.set_defaults(func=_cmd_report)
    return p
