"""``formation-ftc tune`` (the command line of :mod:`formation_ftc.league.tuning`): the parser imports
nothing numeric, so ``--help`` and the completion script answer at once; the command imports the tuner."""

from __future__ import annotations

import argparse
from typing import Any

__all__ = ["add_cli", "OPTIMISERS", "DEFAULT_OPTIMISER", "TRAIN_START"]

#: optimisers of :func:`formation_ftc.league.tuning.minimise`
OPTIMISERS = ("nelder-mead", "powell", "gradient")
#: the default: derivative-free (docs/tuning.md: measured against the gradient on the league)
DEFAULT_OPTIMISER = "nelder-mead"
#: training replicates start here by default (beyond the league's own seeds, which are held out)
TRAIN_START = 10_000


def _cmd_tune(args) -> int:
    import sys

    from formation_ftc.league.tuning import TuneError, tune_league_method, write_tuning

    if not str(args.out).strip():
        raise TuneError("--out: empty path; give a directory, e.g. --out out/league/tuned")
    cases = [c.strip() for c in args.cases.split(",") if c.strip()] if args.cases else None
    step_checks = _league_step_checks(args.step_check_from) if args.step_check_from else None

    result = tune_league_method(
        args.league,
        args.method,
        args.level,
        cases=cases,
        train_seeds=args.train_seeds,
        holdout_seeds=args.holdout_seeds,
        train_start=args.train_start,
        optimiser=args.optimiser,
        max_evaluations=args.max_evaluations,
        margin=args.margin,
        penalty=args.penalty,
        violation_cap=args.violation_cap,
        step_checks=step_checks,
        log=lambda line: print(line, file=sys.stderr, flush=True),
    )
    path = write_tuning(result, args.out)
    if getattr(args, "json", False):
        from formation_ftc.exitcodes import print_json

        print_json({"result": str(path), "tuning": result})  # print_json makes it JSON-safe
        return 0
    obj = result["objective"]["metric"]
    tr, ho = result["train"], result["holdout"]
    print(
        f"{result['method']} @ {result['level']}: {result['optimiser']['name']}, "
        f"{result['optimiser']['evaluations']} evaluations, {result['optimiser']['seconds']:.1f} s"
    )
    for path_, v in result["tuned_gains"].items():
        print(f"  {path_}: {result['paper_gains'][path_]:.6g} -> {v:.6g}")
    for name, s in (("training", tr), ("held-out", ho)):
        print(
            f"  {name}: pass rate {s['paper']['pass_rate']:.2f} -> {s['tuned']['pass_rate']:.2f}, "
            f"mean {obj} {_fmt(s['paper'][f'{obj}_mean'])} -> {_fmt(s['tuned'][f'{obj}_mean'])} "
            f"{result['objective']['units']}"
        )
    print(f"wrote {path}")
    return 0


def _league_step_checks(directory: str) -> dict[str, Any]:
    """The step checks recorded in league directory ``directory`` (``league.json``)."""
    import json
    from pathlib import Path

    from formation_ftc.league.tuning import TuneError

    path = Path(directory) / "league.json"
    try:
        meta = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise TuneError(
            f"--step-check-from {directory}: no readable league.json there ({exc})"
        ) from None
    return dict(meta.get("step_check") or {})


def _fmt(v: Any) -> str:
    return "-" if v is None else format(v, ".4g")


def add_cli(subparsers) -> argparse.ArgumentParser:
    """Add the ``tune`` command to ``subparsers`` (the top-level sub-commands); returns its parser.

    Examples
    --------
    >>> import argparse
    >>> p = argparse.ArgumentParser()
    >>> _ = add_cli(p.add_subparsers())
    >>> p.parse_args(["tune", "lqr", "--out", "o"]).level
    'limited'
    """
    from formation_ftc.exitcodes import add_json_option

    p = subparsers.add_parser(
        "tune", help="choose a league method's gains (its [tune] fields) and report them held out"
    )
    p.add_argument("method", metavar="METHOD", help="league method with a [tune] table")
    p.add_argument(
        "--league", default="translational", help="built-in league name or league TOML file"
    )
    p.add_argument("--level", default="limited", help="actuator level (default: limited)")
    p.add_argument("--out", required=True, help="directory of the result (METHOD--LEVEL.json)")
    p.add_argument(
        "--cases",
        default=None,
        help="comma-separated fault cases (default: every one that applies)",
    )
    p.add_argument("--train-seeds", type=int, default=8, help="training replicates per cell")
    p.add_argument("--holdout-seeds", type=int, default=16, help="held-out replicates per cell")
    p.add_argument(
        "--train-start",
        type=int,
        default=TRAIN_START,
        help="first training replicate (held out: the league's replicates 0 .. N-1)",
    )
    p.add_argument("--optimiser", choices=OPTIMISERS, default=DEFAULT_OPTIMISER, help="optimiser")
    p.add_argument(
        "--max-evaluations", type=int, default=60, help="batch evaluations of the training set"
    )
    p.add_argument(
        "--margin", type=float, default=0.1, help="requirement tightening on training runs [-]"
    )
    p.add_argument("--penalty", type=float, default=100.0, help="weight of the requirement penalty")
    p.add_argument(
        "--violation-cap",
        type=float,
        default=1.0,
        help="largest relative violation one run counts (inf: no cap)",
    )
    p.add_argument(
        "--step-check-from",
        metavar="LEAGUE_DIR",
        default=None,
        help="reuse the step check a league run recorded (default: run it, as `league run` does)",
    )
    add_json_option(p)
    p.set_defaults(func=_cmd_tune)
    return p
