"""``formation-ftc`` command line: run / list / show / check / reproduce / campaign.

Thin edge layer over :mod:`formation_ftc.api`; every command works for every registered method.
Exit codes: 0 success, 1 a required condition failed or a run diverged, 2 bad input.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

__all__ = ["main", "build_parser"]


def _scenario_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("scenario", help="built-in scenario name or path to a TOML file")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="PATH=VALUE",
                   help="override a field, e.g. --set simulation.horizon=100 (repeatable)")


def _cmd_list(args) -> int:
    from formation_ftc.api import list_scenarios

    items = list_scenarios()
    width = max((len(n) for n in items), default=10)
    for name, desc in items.items():
        print(f"{name:<{width}}  {desc}")
    return 0


def _cmd_show(args) -> int:
    from formation_ftc.api import load_scenario
    from formation_ftc.config.loader import dump_toml

    print(dump_toml(load_scenario(args.scenario, args.overrides)), end="")
    return 0


def _print_conditions(conds, as_json: bool) -> int:
    failed_required = [c for c in conds if c.required and c.holds is False]
    if as_json:
        print(json.dumps({"conditions": [c.as_dict() for c in conds],
                          "all_required_hold": not failed_required}, indent=2))
    else:
        from rich.console import Console
        from rich.table import Table

        table = Table(title="Conditions")
        for col in ("condition", "reference", "value", "requirement", "holds", "required"):
            table.add_column(col)
        for c in conds:
            mark = {True: "[green]yes[/]", False: "[red]NO[/]", None: "n/a"}[c.holds]
            table.add_row(c.name, c.reference, c.value, c.requirement, mark, "yes" if c.required else "info")
        Console().print(table)
        for c in conds:
            if c.detail and c.holds is False:
                print(f"- {c.name}: {c.detail}")
        if not conds:
            print("this scenario's method declares no conditions")
    return 1 if failed_required else 0


def _cmd_check(args) -> int:
    from formation_ftc.api import check, load_scenario

    return _print_conditions(check(load_scenario(args.scenario, args.overrides)), args.json)


def _cmd_run(args) -> int:
    import jax
    from rich.console import Console

    from formation_ftc.api import compile_scenario, finish_run, load_scenario, save_result
    from formation_ftc.registry import get_method
    from formation_ftc.sim.engine import SimulationDiverged

    console = Console(stderr=True)
    scenario = load_scenario(args.scenario, args.overrides)
    out_dir = Path(args.out)
    t0 = time.perf_counter()
    with console.status(f"compiling and running {scenario.scenario.name} "
                        f"({scenario.simulation.n_steps:,} steps)..."):
        compiled = compile_scenario(scenario)
        out = jax.jit(compiled.run)(compiled.params)
        jax.block_until_ready(out)
    wall = time.perf_counter() - t0
    code = 0
    try:
        ds, metrics = finish_run(scenario, compiled, out)
    except SimulationDiverged as exc:
        console.print(f"[red]{exc}[/]")
        ds = exc.partial
        from formation_ftc.api import result_metrics

        metrics = result_metrics(ds)
        code = 1
    ds.attrs["wall_time_s"] = wall
    paths = save_result(ds, out_dir, metrics)
    method = get_method(scenario.scenario.method)
    figs = method.plot(ds, scenario, out_dir) if method.plot else []
    console.print(f"wrote {paths['result']}, {paths['metrics']} and {len(figs)} figure(s) in {wall:.2f} s")
    return code


def build_parser() -> argparse.ArgumentParser:
    from formation_ftc import __version__

    parser = argparse.ArgumentParser(prog="formation-ftc", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"formation-ftc {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("list", help="list the built-in scenarios")
    p.set_defaults(func=_cmd_list)

    p = sub.add_parser("show", help="print the resolved TOML of a scenario")
    _scenario_args(p)
    p.set_defaults(func=_cmd_show)

    p = sub.add_parser("check", help="evaluate the scenario's stability/design conditions")
    _scenario_args(p)
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=_cmd_check)

    p = sub.add_parser("run", help="simulate a scenario and write result.nc, metrics.json, figures")
    _scenario_args(p)
    p.add_argument("--out", required=True, help="output directory")
    p.set_defaults(func=_cmd_run)

    for module in ("formation_ftc.report.reproduce", "formation_ftc.campaign.cli"):
        try:
            mod = __import__(module, fromlist=["add_cli"])
        except ImportError as exc:  # pragma: no cover - only while a part is missing
            print(f"warning: {module} unavailable: {exc}", file=sys.stderr)
            continue
        mod.add_cli(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    from formation_ftc.config.loader import ScenarioError
    from formation_ftc.core.expressions import ExpressionError

    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (ScenarioError, ExpressionError, ValueError, KeyError) as exc:
        msg = exc.args[0] if isinstance(exc, KeyError) and exc.args else str(exc)
        print(f"error: {msg}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
