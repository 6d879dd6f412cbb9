"""``formation-ftc falsify`` (the command line of :mod:`formation_ftc.league.falsify`): the parser imports
nothing numeric; the command imports the search."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

__all__ = ["add_cli"]

#: options of ``falsify`` passed to :func:`~formation_ftc.league.falsify.falsify` as they are
_PASSED = "league method level budget seed optimizer population min_magnitude rounds".split()


def _cmd_falsify(args) -> int:
    import math

    import tomli_w

    from formation_ftc.atomic import atomic_write
    from formation_ftc.exitcodes import jsonable, print_json
    from formation_ftc.league.definition import LeagueError
    from formation_ftc.league.falsify import falsify
    from formation_ftc.league.tune_cli import _league_step_checks
    from formation_ftc.provenance import provenance
    from formation_ftc.runout import oserror_as

    t0 = time.perf_counter()
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise LeagueError(f"--out {out}: exists and is not a directory")
    res = falsify(
        step_checks=_league_step_checks(args.step_check_from) if args.step_check_from else None,
        kinds=[k for k in (args.kind or "").split(",") if k] or None,
        **{name: getattr(args, name) for name in _PASSED},
    )
    stem = f"{args.method}--{args.level}--{args.optimizer}-{args.seed}"
    with oserror_as(LeagueError, f"--out {out}: cannot write there"):
        out.mkdir(parents=True, exist_ok=True)
        scenario = out / f"{stem}.toml"
        name = f"falsify-{args.method}-{args.level}"
        description = f"the lowest-robustness run found by formation-ftc falsify ({res.fault})"
        scenario_table = {**res.raw.get("scenario", {}), "name": name, "description": description}
        atomic_write(scenario, tomli_w.dumps({**res.raw, "scenario": scenario_table}))
        record = {
            "kind": "formation-ftc falsification",
            "league": args.league,
            **{k: getattr(res, k) for k in ("method", "level", "optimizer", "seed", "budget")},
            "population": args.population,
            **{k: getattr(res, k) for k in ("found", "runs", "runs_to_violation")},
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


#: the options of ``falsify`` after the method's (``add_method_arguments``): flag -> their keywords
_OPTIONS: dict[str, dict[str, Any]] = {
    "--out": dict(required=True, help="directory of the result and the falsifying scenario"),
    "--budget": dict(type=int, default=200, help="most runs (default 200)"),
    "--population": dict(type=int, default=8, help="runs per batch (default 8)"),
    "--seed": dict(type=int, default=0, help="seed of the optimiser (default 0)"),
    "--optimizer": dict(
        choices=("cma", "random"), default="cma", help="CMA-ES or uniform sampling"
    ),
    "--kind": dict(
        help="comma-separated fault kinds to search (default every actuator kind of the battery)"
    ),
    "--min-magnitude": dict(
        action="store_true",
        help="then the smallest breaking severity of each kind, at its worst run found",
    ),
    "--rounds": dict(type=int, default=3, help="section rounds of --min-magnitude (default 3)"),
}


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
    add_method_arguments(p, "league method", _OPTIONS)
    add_json_option(p)
    p.set_defaults(func=_cmd_falsify)
    return p
