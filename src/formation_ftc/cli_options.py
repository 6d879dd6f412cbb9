"""Command-line arguments that several ``formation-ftc`` commands share, or that the completion script
needs without the command's module: imports nothing numeric (the completion script builds every parser
and must not import JAX)."""

from __future__ import annotations

import argparse
from collections.abc import Iterable
from pathlib import Path

from formation_ftc.exitcodes import add_json_option

__all__ = ["add_budget_options", "add_executor_options", "add_reproduce_parser"]


def add_budget_options(
    parser: argparse.ArgumentParser, *, batch: str, whole: str | None = None
) -> None:
    """``--max-memory``, ``--max-run-steps`` and, with ``whole``, ``--max-campaign-steps``
    (formation_ftc.limits), for ``run``, ``campaign run``, ``league run`` and ``tune``: ``batch`` and
    ``whole`` say what the first and last one bound."""
    parser.add_argument(
        "--max-memory",
        metavar="SIZE",
        help=f"memory budget of {batch}, e.g. 32GB (default 8 GiB or half the RAM; 0 = none)",
    )
    parser.add_argument(
        "--max-run-steps",
        metavar="N",
        help="integration steps allowed per run (default 1e9; 0 = none)",
    )
    if whole is not None:
        parser.add_argument(
            "--max-campaign-steps",
            metavar="N",
            help=f"run-steps allowed in {whole} (default 1e11; 0 = none)",
        )


def add_executor_options(
    parser: argparse.ArgumentParser, *, workers: str, connect_timeout: bool = False
) -> None:
    """The executor options of ``campaign run`` and ``league run``: ``--workers`` (its help: ``workers``),
    the Dask ones (``--scheduler`` or ``--dask-local``) and, with ``connect_timeout``,
    ``--connect-timeout``."""
    parser.add_argument("--workers", type=int, help=workers)
    g = parser.add_mutually_exclusive_group()
    g.add_argument("--scheduler", metavar="ADDR", help="Dask scheduler tcp://HOST:PORT")
    g.add_argument(
        "--dask-local",
        metavar="N",
        type=int,
        help="start a Dask LocalCluster with N worker processes",
    )
    if connect_timeout:
        parser.add_argument(
            "--connect-timeout",
            metavar="S",
            type=float,
            help="seconds allowed for the Dask scheduler handshake (default 30)",
        )


def add_reproduce_parser(subparsers, papers: Iterable[str]) -> argparse.ArgumentParser:
    """The ``reproduce`` sub-command of ``subparsers`` with its arguments (PAPER: one of ``papers`` or
    'all') but no handler: :func:`formation_ftc.report.reproduce.add_cli` sets it; the completion
    script, which must not import that module (JAX), uses this alone.

    Examples
    --------
    >>> p = argparse.ArgumentParser()
    >>> q = add_reproduce_parser(p.add_subparsers(), ["li2020"])
    >>> p.parse_args(["reproduce", "all", "--out", "o"]).paper
    ['all']
    """
    p = subparsers.add_parser(
        "reproduce",
        help="reproduce the papers' studies and write an HTML report",
        description="Run the paper reproductions and write DIR/index.html, DIR/summary.json and one "
        "folder per paper. Exit status: 0 all ran, 1 a paper failed, 2 bad input.",
    )
    valid = ", ".join(papers)
    p.add_argument("paper", nargs="+", metavar="PAPER", help=f"paper name ({valid}) or 'all'")
    p.add_argument("--out", required=True, type=Path, metavar="DIR", help="report directory")
    p.add_argument(
        "--force",
        action="store_true",
        help="write into an existing non-empty directory that is not a previous report",
    )
    p.add_argument(
        "--no-3d",
        dest="include_3d",
        action="store_false",
        help="leave out the interactive 3-D trajectory views (smaller page)",
    )
    p.add_argument(
        "--profile",
        action="store_true",
        help="time each paper's compile / run / post-processing / plotting / report phases, print "
        "them as a table and store them in the report's run metadata",
    )
    p.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="papers computed side by side in N worker processes (default: one per CPU core, at "
        "most one per paper; 1: one after the other in this process); same numbers either way",
    )
    p.add_argument(
        "--league",
        action="append",
        type=Path,
        metavar="DIR",
        help="link this league directory's leaderboard from the report (repeatable; leaderboards in "
        "DIR/*/leaderboard/ of the report directory are linked anyway)",
    )
    add_json_option(p)
    return p
