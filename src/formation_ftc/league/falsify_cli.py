"""``formation-ftc falsify`` (the command line of :mod:`formation_ftc.league.falsify`): the parser imports
nothing numeric; the command imports the search."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

__all__ = ["add_cli"]


def _cmd_falsify(args) -> int:
    import math

    import tomli_w

    from formation_ftc.atomic import atomic_write
    from formation_ftc.exitcodes import jsonable, print_json
    from formation_ftc.league.definition import LeagueError
    from formation_ftc.league.falsify import falsify
    from formation_ftc.league.tune_cli import _league_step_checks
    from formation_ftc.provenance import provenance

    t0 = time.perf_counter()
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise LeagueError(f"--out {out}: exists and is not a directory")
    checks = _league_step_checks(args.step_check_from) if args.step_check_from else None
    res = falsify(
        args.league,
        args.method,
        args.level,
        budget=args.budget,
        seed=args.seed,
        optimizer=args.optimizer,
        population=args.population,
        step_checks=checks,
        kinds=[k for k in (args.kind or "").split(",") if k] or None,
        min_magnitude=args.min_magnitude,
        rounds=args.rounds,
    )
    stem = f"{args.method}--{args.level}--{args.optimizer}-{args.seed}"
    try:
        out.mkdir(parents=True, exist_ok=True)
        scenario = out / f"{stem}.toml"
        name = f"falsify-{args.method}-{args.level}"
        description = f"the lowest-robustness run found by formation-ftc falsify ({res.fault})"
        scenario_table = {**res.raw.get("scenario", {}), "name": name, "description": description}
        atomic_write(scenario, tomli_w.dumps({**res.raw, "scenario": scenario_table}))
        record = {
            "kind": "formation-ftc falsification",
            "league": args.league,
            "method": res.method,
            "level": res.level,
            "optimizer": res.optimizer,
            "seed": res.seed,
            "budget": res.budget,
            "population": args.population,
            "found": res.found,
            "runs": res.runs,
            "runs_to_violation": res.runs_to_violation,
            "robustness": res.best,  # None when not finite (jsonable, below)
            "diverged": res.best == -math.inf,
            "fault": res.fault,
            "kinds": sorted({*res.worst}),
            "worst_by_kind": {
                k: {"robustness": rb, "fault": f} for k, (rb, f) in res.worst.items()
            },
            "min_magnitude": res.magnitudes,
            "scenario": str(scenario),
            "history": res.history,
            "seconds": res.seconds,
            "provenance": provenance(),
        }
        result = out / f"{stem}.json"
        atomic_write(result, json.dumps(jsonable(record), indent=1))
    except OSError as exc:
        raise LeagueError(f"--out {out}: cannot write there ({exc.strerror or exc})") from None
    if args.json:
        print_json({**record, "result": str(result), "wall_time": time.perf_counter() - t0})
        return 0
    verdict = f"no violation in {res.runs} runs"
    if res.found:
        verdict = f"violation after {res.runs_to_violation} runs"
    print(
        f"{res.method} @ {res.level}, {res.optimizer} (seed {res.seed}): {verdict}; lowest "
        f"robustness {res.best:.4g}: {res.fault}"
    )
    for m in res.magnitudes or ():
        if m["severity"] is None:
            print(f"  {m['kind']}: no magnitude; robustness {m['robustness']:.4g} at its worst run")
            continue
        lo, hi = m["largest_holding"], m["smallest_violating"]
        if hi is None:
            bracket = f"holds up to {lo:.3g}"
        elif lo is None:
            bracket = f"breaks with no fault (at {hi:.3g})"
        else:
            bracket = f"breaks between {lo:.3g} and {hi:.3g}"
        shape = "" if m["monotone"] else " (robustness not monotone in the samples)"
        print(f"  {m['kind']}: {m['severity']} {bracket}{shape}, at {m['at']}")
    print(f"wrote {scenario} (replay: formation-ftc run {scenario}) and {result}")
    return 0


def add_cli(subparsers) -> argparse.ArgumentParser:
    """Add the ``falsify`` command to ``subparsers``; returns its parser.

    Examples
    --------
    >>> p = argparse.ArgumentParser()
    >>> _ = add_cli(p.add_subparsers())
    >>> p.parse_args(["falsify", "lqr", "--out", "o"]).budget
    200
    """
    from formation_ftc.exitcodes import add_json_option
    from formation_ftc.league.tune_cli import add_method_arguments

    p = subparsers.add_parser(
        "falsify", help="search a league method for a run that violates the requirement"
    )
    add_method_arguments(p, "league method")
    p.add_argument(
        "--out", required=True, help="directory of the result and the falsifying scenario"
    )
    p.add_argument("--budget", type=int, default=200, help="most runs (default 200)")
    p.add_argument("--population", type=int, default=8, help="runs per batch (default 8)")
    p.add_argument("--seed", type=int, default=0, help="seed of the optimiser (default 0)")
    p.add_argument(
        "--optimizer", choices=("cma", "random"), default="cma", help="CMA-ES or uniform sampling"
    )
    p.add_argument(
        "--kind",
        help="comma-separated fault kinds to search (default every actuator kind of the battery)",
    )
    p.add_argument(
        "--min-magnitude",
        action="store_true",
        help="then the smallest breaking severity of each kind, at its worst run found",
    )
    p.add_argument(
        "--rounds", type=int, default=3, help="section rounds of --min-magnitude (default 3)"
    )
    add_json_option(p)
    p.set_defaults(func=_cmd_falsify)
    return p
