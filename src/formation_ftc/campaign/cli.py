"""``formation-ftc campaign {list, run, report}``.

The main command line calls :func:`add_cli` with its sub-parsers; this module also runs alone:
``python -m formation_ftc.campaign.cli run NAME_OR_FILE --out DIR``. ``list``, ``run`` and ``report``
take ``--json`` (one JSON document on stdout, progress on stderr; schemas in docs/cli.md).
"""

from __future__ import annotations

import argparse
import sys

from formation_ftc.cli_options import add_budget_options, add_executor_options
from formation_ftc.exitcodes import add_json_option, print_json

__all__ = ["add_cli", "main"]


def _builtin_texts() -> dict[str, str]:
    """Name -> TOML text of every built-in campaign, read without importing the campaign model
    (:func:`formation_ftc.campaign.spec.builtin_campaigns` reads the same files; its module imports
    pydantic and scipy.stats, which ``campaign list`` does not use)."""
    from importlib import resources

    d = resources.files("formation_ftc") / "campaign" / "builtin"
    entries = sorted((e for e in d.iterdir() if e.name.endswith(".toml")), key=lambda e: e.name)
    return {e.name[:-5]: e.read_text(encoding="utf-8") for e in entries}


def _cmd_list(args) -> int:
    import tomllib

    rows = []
    for name, text in _builtin_texts().items():
        meta = tomllib.loads(text).get("campaign", {})
        if args.json:
            base = meta.get("base", [])
            rows.append(
                {
                    "name": name,
                    "description": str(meta.get("description", "")),
                    "base": [str(b) for b in (base if isinstance(base, list) else [base])],
                    "runs": meta.get("runs") if isinstance(meta.get("runs"), int) else None,
                }
            )
        else:
            print(f"{name}  {meta.get('description', '')}")
    if args.json:
        print_json({"campaigns": rows})
    return 0


#: memory of one local worker process before its batch: Python, JAX and the compiled programs [bytes]
WORKER_BYTES = 2**29


def _capped(requested: int | None, what: str, batch_bytes: int) -> int | None:
    """``--workers`` / ``--dask-local``: at most the schedulable cores and what the available memory holds
    (one warning line on stderr when lowered); None and 1 stay as they are."""
    from formation_ftc.campaign.executors import cap_workers

    if requested is None or requested <= 1:
        return requested
    return cap_workers(requested, per_worker_bytes=WORKER_BYTES + batch_bytes, what=what)


def _cmd_run(args) -> int:
    import time

    started = time.perf_counter()  # the wall time and rate count from here, imports included
    import contextlib

    from rich.console import Console

    from formation_ftc.campaign.executors import make_executor
    from formation_ftc.campaign.runner import make_plan, run_campaign
    from formation_ftc.campaign.spec import CampaignError
    from formation_ftc.limits import Budgets, check_campaign_budgets

    console = Console(stderr=True)
    if not str(args.out).strip():
        raise CampaignError(
            "--out: empty path; give the results directory, e.g. --out out/campaign1"
        )
    # with --json, standard output carries the one document: anything printed meanwhile goes to stderr
    with contextlib.redirect_stdout(sys.stderr) if args.json else contextlib.nullcontext():
        plan = make_plan(args.campaign, runs=args.runs, chunk_size=args.chunk_size)
        budgets = Budgets.resolve(args.max_memory, args.max_run_steps, args.max_campaign_steps)
        # before anything is compiled or written
        batch = check_campaign_budgets(plan, budgets)["batch_memory"]
        executor = make_executor(
            workers=_capped(args.workers, "--workers", batch),
            scheduler=args.scheduler,
            dask_local=_capped(args.dask_local, "--dask-local", batch),
            connect_timeout=args.connect_timeout,
        )
        outcome = run_campaign(
            plan, args.out, executor=executor, progress=not args.no_progress, started=started
        )
    console.print(f"campaign done ({outcome.executor}): {outcome}", soft_wrap=True, markup=False)
    if args.json:
        print_json(_run_document(outcome))
    return 0


def _run_document(outcome) -> dict:
    """The ``campaign run --json`` document (docs/cli.md) of a :class:`CampaignOutcome`."""
    from pathlib import Path

    out = Path(outcome.out_dir)
    return {
        "campaign": outcome.name,
        "dir": str(out),
        "executor": outcome.executor,
        "exit_code": 0,
        "runs": {
            "total": outcome.n_planned,
            "done": outcome.n_runs,
            "computed": outcome.n_computed,
            "skipped": outcome.n_kept,
            "ok": outcome.n_runs - outcome.n_failed,
            "failed": outcome.n_failed,
            "diverged": outcome.n_diverged,
        },
        "chunks": {
            "total": outcome.chunks_total,
            "computed": outcome.chunks_computed,
            "skipped": outcome.chunks_resumed,
        },
        "wall_time": outcome.wall_s,
        "rate": outcome.rate,
        "outputs": {
            "manifest": str(out / "manifest.json"),
            "chunks": str(out / "chunks"),
            "traces": sorted(str(p) for p in (out / "traces").glob("run-*.nc")),
        },
        "units": {"wall_time": "s", "rate": "s-1"},
    }


def _cmd_report(args) -> int:
    from pathlib import Path

    from rich.console import Console

    from formation_ftc.campaign.report import write_report

    console = None if args.json else Console(width=None if sys.stdout.isatty() else 160)
    summary, figures = write_report(args.dir, console=console, plots=not args.no_plots)
    if args.json:
        from formation_ftc.campaign.storage import CampaignStore

        report = Path(args.dir) / "report"
        units = CampaignStore.read(args.dir).units()  # of the chunks' columns (parquet_units)
        print_json(
            {
                "dir": str(args.dir),
                "summary": summary,
                "units": {
                    c.removeprefix("metric:"): u
                    for c, u in units.items()
                    if c.startswith("metric:")
                },
                "outputs": {
                    "summary_json": str(report / "summary.json"),
                    "summary_csv": str(report / "summary.csv"),
                    "figures": [str(f) for f in figures],
                },
            }
        )
        return 0
    print(f"wrote {args.dir}/report/summary.json, summary.csv and {len(figures)} figure(s)")
    return 0


def add_cli(subparsers) -> argparse.ArgumentParser:
    """Add the ``campaign`` command (with ``list``, ``run``, ``report``) to ``subparsers``."""
    p = subparsers.add_parser(
        "campaign", help="Monte Carlo campaigns: list, run (resumable), report"
    )
    sub = p.add_subparsers(dest="campaign_command", required=True)

    q = sub.add_parser("list", help="list the built-in campaigns (name first)")
    add_json_option(q)
    q.set_defaults(func=_cmd_list)

    q = sub.add_parser("run", help="run or resume a campaign into a results directory")
    q.add_argument(
        "campaign", metavar="NAME_OR_FILE", help="built-in campaign name or campaign TOML file"
    )
    q.add_argument(
        "--out", required=True, help="results directory (resumed when it holds this campaign)"
    )
    q.add_argument("--runs", type=int, help="runs per grid point (overrides the file)")
    q.add_argument("--chunk-size", type=int, help="runs per vmap batch (overrides the file)")
    add_executor_options(
        q,
        workers="local worker processes (spawn); 1 = in-process; default: one per CPU core (at most "
        "one per chunk), in-process for campaigns under 10 million run-steps",
        connect_timeout=True,
    )
    add_budget_options(q, batch="one batch of chunk-size runs", whole="the whole campaign")
    q.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_json_option(q)
    q.set_defaults(func=_cmd_run)

    q = sub.add_parser(
        "report", help="summary statistics and sensitivity plots of a campaign directory"
    )
    q.add_argument("dir", metavar="DIR", help="campaign results directory")
    q.add_argument("--no-plots", action="store_true", help="tables only")
    add_json_option(q)
    q.set_defaults(func=_cmd_report)
    return p


def main(argv: list[str] | None = None) -> int:
    """Stand-alone entry point: ``main(["run", ...])`` or ``main(["campaign", "run", ...])``."""
    from formation_ftc.exitcodes import lossy_stderr, run_guarded

    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] != "campaign":
        argv = ["campaign", *argv]
    parser = argparse.ArgumentParser(prog="formation-ftc")
    add_cli(parser.add_subparsers(dest="command", required=True))
    with lossy_stderr():
        args = parser.parse_args(argv)
        return run_guarded(args.func, args)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
