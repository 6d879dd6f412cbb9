"""``formation-ftc tune`` (the command line of :mod:`formation_ftc.league.tuning`): the parser imports
nothing numeric, so ``--help`` and the completion script answer at once; the command imports the tuner."""

from __future__ import annotations

import argparse
from typing import Any

__all__ = ["add_cli"]

from formation_ftc.league.tuning_options import DEFAULT_OPTIMISER, OPTIMISERS, TRAIN_START

#: options of ``tune`` passed to :func:`~formation_ftc.league.tuning.tune_league_method` as they are
_PASSED = (
    "league method level train_seeds holdout_seeds fresh_seeds train_start optimiser "
    "max_evaluations margin penalty violation_cap force"
).split()


def _cmd_tune(args) -> int:
    import time

    from formation_ftc.league import tuning
    from formation_ftc.league.cli import _log, _quiet
    from formation_ftc.limits import Budgets

    t0 = time.perf_counter()
    if not str(args.out).strip():
        raise tuning.TuneError("--out: empty path; give a directory, e.g. --out out/league/tuned")
    budgets = Budgets.resolve(args.max_memory, args.max_run_steps, args.max_campaign_steps)
    # before anything is computed: where the result goes (and its journal)
    tuning.check_tune_out(args.out, args.method, args.level, force=args.force)
    journal = tuning.journal_path(args.out, args.method, args.level)
    result = tuning.tune_league_method(
        cases=[c.strip() for c in args.cases.split(",") if c.strip()] if args.cases else None,
        gains=_gains(args.gains) if args.gains is not None else None,
        step_checks=_league_step_checks(args.step_check_from) if args.step_check_from else None,
        log=_log(args),
        budgets=budgets,
        journal=journal,
        progress=not _quiet(args),
        **{name: getattr(args, name) for name in _PASSED},
    )
    path = tuning.write_tuning(result, args.out)
    journal.unlink(missing_ok=True)  # the result holds every evaluation (optimiser.history)
    wall = time.perf_counter() - t0
    if getattr(args, "json", False):
        from formation_ftc.exitcodes import print_json

        print_json(  # print_json makes it JSON-safe
            {"result": str(path), "tuning": result, "wall_time": wall, "units": {"wall_time": "s"}}
        )
        return 0
    obj = result["objective"]["metric"]
    print(
        f"{result['method']} @ {result['level']}: {result['optimiser']['name']}, "
        f"{result['optimiser']['evaluations']} evaluations, {wall:.1f} s"
    )
    for path_, v in result["tuned_gains"].items():
        print(f"  {path_}: {result['paper_gains'][path_]:.6g} -> {v:.6g}")
    for name, key in (("training", "train"), ("held-out", "holdout"), ("fresh", "fresh")):
        if (s := result[key]) is None:
            continue
        print(
            f"  {name}: pass rate {s['paper']['pass_rate']:.2f} -> {s['tuned']['pass_rate']:.2f}, "
            f"mean {obj} {_fmt(s['paper'][f'{obj}_mean'])} -> {_fmt(s['tuned'][f'{obj}_mean'])} "
            f"{result['objective']['units']} (over {s['paper']['finished']} -> "
            f"{s['tuned']['finished']} of {s['tuned']['runs']} runs: the diverged left out)"
        )
    print(f"wrote {path}")
    return 0


def _league_step_checks(directory: str) -> dict[str, Any]:
    """The step checks recorded in league directory ``directory`` (``league.json``, field
    ``step_check``: ``{method: record}``, each with a positive ``chosen_dt`` [s]); TuneError naming
    the file and the field when it is missing, damaged or mistyped."""
    import json
    from pathlib import Path

    from pydantic import TypeAdapter, ValidationError

    from formation_ftc.league.runner import LEAGUE_FILE, StepCheckRecord, record_error
    from formation_ftc.league.tuning import TuneError

    what = f"--step-check-from {directory}"
    path = Path(directory) / LEAGUE_FILE
    if not path.is_file():
        raise TuneError(
            f"{what}: no {path} (give a league directory that `formation-ftc league run` wrote)"
        )
    try:
        meta = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        reason = getattr(exc, "strerror", None) or exc
        raise TuneError(f"{what}: {path} is damaged or unreadable ({reason})") from None
    if not isinstance(meta, dict):
        raise TuneError(f"{what}: {path} is not a league description (not a JSON object)")
    checks = meta.get("step_check", {})
    try:
        TypeAdapter(dict[str, StepCheckRecord]).validate_python(checks, strict=True)
    except ValidationError as exc:
        raise TuneError(f"{what}: {record_error(path, exc, 'step_check')}") from None
    return dict(checks)


def _gains(text: str) -> dict[str, float]:
    """``--gains "controller.k=0.02,controller.lam=35"`` as {path: value}; TuneError naming the item."""
    from formation_ftc.league.tuning import TuneError

    out: dict[str, float] = {}
    for item in (t.strip() for t in text.split(",")):
        path, eq, value = item.partition("=")
        try:
            v = float(value)
        except ValueError:
            v = float("nan")
        if not eq or not path.strip() or v != v or abs(v) == float("inf"):
            raise TuneError(
                f"--gains: {item!r} is not FIELD=NUMBER (e.g. --gains controller.k=0.02,controller.lam=35)"
            )
        out[path.strip()] = v
    return out


def add_method_arguments(
    p: argparse.ArgumentParser, method_help: str, options: dict[str, dict[str, Any]]
) -> None:
    """The arguments of ``tune`` and ``falsify``: those naming one league method and level (METHOD,
    ``--league``, ``--level`` and ``--step-check-from``), then the command's ``options`` (flag -> the
    keywords of ``add_argument``)."""
    p.add_argument("method", metavar="METHOD", help=method_help)
    p.add_argument(
        "--league", default="translational", help="built-in league name or league TOML file"
    )
    p.add_argument("--level", default="limited", help="actuator level (default: limited)")
    p.add_argument(
        "--step-check-from",
        metavar="LEAGUE_DIR",
        help="reuse the step check a league run recorded (default: run it, as `league run` does)",
    )
    for flag, keywords in options.items():
        p.add_argument(flag, **keywords)


def _fmt(v: Any) -> str:
    return "-" if v is None else format(v, ".4g")


#: the options of ``tune`` after the method's (:func:`add_method_arguments`): flag -> their keywords
_OPTIONS: dict[str, dict[str, Any]] = {
    "--out": dict(
        required=True,
        help="directory of the result (METHOD--LEVEL.json; new, empty or of tuning results); a "
        "killed tuning resumes from its journal there (METHOD--LEVEL.journal.jsonl)",
    ),
    "--cases": dict(help="comma-separated fault cases (default: every one that applies)"),
    "--train-seeds": dict(type=int, default=8, help="training replicates per cell"),
    "--holdout-seeds": dict(type=int, default=16, help="held-out replicates per cell"),
    "--fresh-seeds": dict(
        type=int,
        help="replicates per cell neither the league nor the training uses (default: as many as "
        "--holdout-seeds; 0: none)",
    ),
    "--gains": dict(
        metavar="FIELD=VALUE,...",
        help="evaluate these gains against the paper's (held-out and fresh replicates), with no "
        "training",
    ),
    "--train-start": dict(
        type=int,
        default=TRAIN_START,
        help="first training replicate (held out: the league's replicates 0 .. N-1)",
    ),
    "--optimiser": dict(choices=OPTIMISERS, default=DEFAULT_OPTIMISER, help="optimiser"),
    "--max-evaluations": dict(type=int, default=60, help="batch evaluations of the training set"),
    "--margin": dict(type=float, default=0.1, help="requirement tightening on training runs [-]"),
    "--penalty": dict(type=float, default=100.0, help="weight of the requirement penalty"),
    "--violation-cap": dict(
        type=float, default=1.0, help="largest relative violation one run counts (inf: no cap)"
    ),
    "--force": dict(
        action="store_true",
        help="replace this method's result at this level in --out, and discard a journal of another "
        "tuning there (default: refuse both)",
    ),
}


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
    from formation_ftc.cli_options import add_budget_options
    from formation_ftc.exitcodes import add_json_option

    p = subparsers.add_parser(
        "tune", help="choose a league method's gains (its [tune] fields) and report them held out"
    )
    add_method_arguments(p, "league method with a [tune] table", _OPTIONS)
    add_budget_options(
        p, batch="the training batch", whole="the whole tuning (every evaluation, held-out runs)"
    )
    add_json_option(p)
    p.set_defaults(func=_cmd_tune)
    return p
