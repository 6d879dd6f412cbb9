"""formation-ftc command line: list, show, check, schema, run, plot, reproduce, campaign, league,
completion.

Thin edge layer over formation_ftc.api; every command works for every registered method. Heavy
modules (JAX, SciPy, pandas) are imported by the commands that need them, so --help, --version,
list and completion answer at once. Exit codes: 0 success, 1 a required condition failed, a run
diverged or stdout could not be written, 2 bad input, 3 unexpected error (formation_ftc.exitcodes).

``--json`` (every command that prints results: list, show, check, run, plot, reproduce, campaign
list/run/report, league list/run/report, tune) prints one JSON document on stdout with typed values
(numbers, booleans, null) and units in separate keys, progress on stderr; its schemas are in
docs/cli.md.
"""

from __future__ import annotations

import argparse
import importlib
import json
import re
import sys
import time
from pathlib import Path
from typing import Any, NoReturn

from formation_ftc.errors import InputError
from formation_ftc.exitcodes import add_json_option, lossy_stderr, print_json, print_json_error

__all__ = ["main", "build_parser", "completion_parser", "lossy_stderr", "print_json"]

EXIT_CODES = (
    "exit status:\n"
    "  0  success\n"
    "  1  a required condition failed or a run diverged (partial results are still written), or\n"
    "     standard output could not be written\n"
    "  2  bad input (the message names the file, the field and the allowed range)\n"
    "  3  unexpected error (one line, and the path of a file holding the traceback)"
)

#: command path -> (description, examples); shown by ``formation-ftc COMMAND --help`` as plain text
HELP: dict[str, tuple[str, list[str]]] = {
    "": (
        "Simulate, design and verify fault-tolerant control of spacecraft formations (JAX, float64).",
        [
            "formation-ftc list",
            "formation-ftc run cw-pd-fault --out out/run1 --set simulation.horizon=300",
            "formation-ftc reproduce all --out out/reproduction",
            "formation-ftc COMMAND --help",
        ],
    ),
    "list": (
        "List the built-in scenarios, one line each (name, then description).",
        ["formation-ftc list", "formation-ftc list | grep li2020", "formation-ftc list --json"],
    ),
    "show": (
        "Print the fully resolved TOML of a scenario (defaults filled in, --set overrides applied), "
        "each field followed by its unit and meaning as a comment. `show` checks every field of every "
        "section; `check` also builds the loop to check that the components fit together.",
        [
            "formation-ftc show li2020-thm1",
            "formation-ftc show my-scenario.toml --set controller.kp=3",
            "formation-ftc show cw-pd-fault --json",
        ],
    ),
    "check": (
        "Evaluate the theorem and design conditions of a scenario's method before any run.",
        ["formation-ftc check li2020-thm2-delays", "formation-ftc check gui2022-lof2tc --json"],
    ),
    "schema": (
        "Print the JSON Schema of a method's scenario file (for editor completion and validation). "
        "Without METHOD, list the registered methods.",
        ["formation-ftc schema", "formation-ftc schema composed > composed.schema.json"],
    ),
    "run": (
        "Simulate a scenario and write DIR/result.nc, DIR/metrics.json and DIR/index.html; with "
        "--figures also the standard and the method's figures (PNG), which `formation-ftc plot DIR` "
        "draws later otherwise. The time printed is the wall time of the whole command; the "
        "simulation's own time follows it.",
        [
            "formation-ftc run cw-pd-fault --out out/run1",
            "formation-ftc run cw-pd-fault --out out/run1 --figures --set simulation.horizon=300",
            "formation-ftc run cw-free-drift --out out/run2 --json",
        ],
    ),
    "plot": (
        "Draw the figures of a saved result from its files alone (no simulation): a run's standard "
        "and method figures from DIR/result.nc (index.html refreshed), a campaign's report figures, "
        "a league's leaderboard figures.",
        [
            "formation-ftc plot out/run1",
            "formation-ftc plot out/run1 --format svg",
            "formation-ftc plot out/campaign1 --json",
        ],
    ),
    "reproduce": (
        "Run the papers' simulation studies and write DIR/index.html, DIR/summary.json and one "
        "folder per paper.",
        [
            "formation-ftc reproduce li2020 --out out/li2020",
            "formation-ftc reproduce all --out out/reproduction",
            "formation-ftc reproduce li2020 --out out/li2020 --profile",
            "formation-ftc reproduce yang2013 --out out/yang2013 --json",
        ],
    ),
    "campaign": (
        "Monte Carlo campaigns: list the built-in ones, run (resumable) and report.",
        [
            "formation-ftc campaign list",
            "formation-ftc campaign run cw-pd-gains --out out/c --runs 20",
            "formation-ftc campaign report out/c",
        ],
    ),
    "league": (
        "FTC league: every method on one realistic truth (J2, drag) under the same fault battery, "
        "ranked on the same scores.",
        [
            "formation-ftc league list",
            "formation-ftc league run translational --quick --out out/league",
            "formation-ftc league report out/league",
        ],
    ),
    "league list": (
        "List the built-in leagues (name, description, methods).",
        ["formation-ftc league list", "formation-ftc league list --json"],
    ),
    "league run": (
        "Run (or resume) a league into a directory and write its leaderboard.",
        [
            "formation-ftc league run translational --quick --out out/league",
            "formation-ftc league run attitude --quick --out out/att --workers 2",
        ],
    ),
    "league report": (
        "(Re)write the leaderboard (index.html, leaderboard.json, Parquet) of a league directory.",
        ["formation-ftc league report out/league", "formation-ftc league report out/league --json"],
    ),
    "tune": (
        "Choose a league method's [tune] gains for one actuator level (training seeds), report them on "
        "held-out seeds; `league report` shows them in its tuned column (docs/tuning.md).",
        [
            "formation-ftc tune yang2013 --league translational --level limited --out out/league/tuned",
            "formation-ftc tune li2020-thm1 --cases none,loe-50 --train-seeds 4 --out out/league/tuned",
        ],
    ),
    "falsify": (
        "Search the fault (kind, channel, onset, magnitude), the initial errors and the noise seed of a "
        "league method for a run that violates the requirement (CMA-ES or random sampling); write it as "
        "a scenario that `formation-ftc run` replays (docs/falsification.md).",
        [
            "formation-ftc falsify lqr --league translational --level limited --out out/falsify",
            "formation-ftc falsify azizi2009 --level unsaturated --optimizer random --out out/falsify",
        ],
    ),
    "campaign list": (
        "List the built-in campaigns (name, then description).",
        ["formation-ftc campaign list", "formation-ftc campaign list --json"],
    ),
    "campaign run": (
        "Run a campaign into a results directory; run the same command again to resume a "
        "killed one.",
        [
            "formation-ftc campaign run cw-pd-gains --out out/c --runs 20",
            "formation-ftc campaign run my-campaign.toml --out out/c --dask-local 4",
            "formation-ftc campaign run cw-pd-gains --out out/c --json",
        ],
    ),
    "campaign report": (
        "Summary statistics (summary.json, summary.csv) and sensitivity plots of a "
        "campaign directory.",
        [
            "formation-ftc campaign report out/c",
            "formation-ftc campaign report out/c --json --no-plots",
        ],
    ),
    "completion": (
        "Print the shell completion script of formation-ftc (sub-commands, options, built-in "
        "scenario, campaign, league and paper names); install it once, see docs/cli.md.",
        [
            "formation-ftc completion bash > ~/.local/share/bash-completion/completions/formation-ftc",
            "formation-ftc completion zsh > ~/.zfunc/_formation-ftc",
            "formation-ftc completion tcsh > ~/.formation-ftc.completion.csh",
        ],
    ),
}

_VERBOSITY = 0  # -1 quiet, 0 normal, 1 verbose (set by main)
_ONE_SHOT_PROCESS = False  # main() runs one command and the process ends (set by main)
_STARTED = 0.0  # time.perf_counter() when main() began


def _check_scenario_name(name: str) -> None:
    """Bad input with a "did you mean" when ``name`` is neither a file nor a built-in scenario."""
    from formation_ftc.config.loader import ScenarioError
    from formation_ftc.suggest import did_you_mean

    try:
        if name.endswith(".toml") or Path(name).exists():
            return
    except (OSError, ValueError):  # a path text the system refuses: the loader reports it
        return
    names = _resource_names("scenarios")
    if name not in names:
        raise ScenarioError(
            f"unknown scenario {name!r}: not a file and not a built-in scenario"
            f"{did_you_mean(name, names)}; see `formation-ftc list`"
        )


def _field_hints(scenario: str, overrides: list[str]) -> str:
    """ "did you mean" lines for unknown fields of a scenario (file or --set paths); "" if none."""
    from formation_ftc.config import loader
    from formation_ftc.suggest import unknown_fields

    try:
        raw, _ = loader.read_raw(scenario)
        raw = loader.apply_overrides(raw, overrides)
        schema = _scenario_schema(raw)
    except Exception:  # noqa: BLE001 - hints are best effort; the original error is reported anyway
        return ""
    return "".join(f"\n  {u.message()}" for u in unknown_fields(raw, schema) if u.suggestions)


def _scenario_schema(raw: dict) -> dict:
    """The JSON Schema of the scenario ``raw``'s method; in a composed scenario each slot table gets
    the schema of the component type it names (its option of ``schema composed``), so that its
    fields have units, comments and hints."""
    method = str(raw["scenario"].get("method", "composed"))
    if method != "composed":
        from formation_ftc.registry import get_method

        return get_method(method).schema.model_json_schema()
    from formation_ftc.shipped_schema import composed_schema

    schema = composed_schema()
    properties = dict(schema["properties"])
    for slot, table in raw.items():
        options = properties.get(slot, {}).get("oneOf") if isinstance(table, dict) else None
        if options is None:
            continue
        name = str(table.get("type"))
        chosen = [o for o in options if o["properties"]["type"]["const"] == name]
        properties[slot] = chosen[0] if chosen else {"description": properties[slot]["description"]}
    return {**schema, "properties": properties}


def _load(args, build: bool = True):
    """The validated scenario of ``args.scenario`` with ``--set`` overrides; errors get "did you mean".
    ``build=False``: every field checked, the loop not built (no JAX imported: ``show``)."""
    from formation_ftc.config import loader
    from formation_ftc.config.loader import ScenarioError

    _check_scenario_name(args.scenario)
    try:
        if not build:  # what api.load_scenario does, without importing the api (and JAX)
            raw, source = loader.read_raw(args.scenario)
            return loader.validate(loader.apply_overrides(raw, args.overrides), source, build=False)
        from formation_ftc.api import load_scenario

        return load_scenario(args.scenario, args.overrides)
    except ScenarioError as exc:
        hints = _field_hints(args.scenario, args.overrides)
        if not hints:
            raise
        raise ScenarioError(f"{exc}{hints}") from None


def _command(sub, name: str, func, short: str, scenario: bool = False) -> argparse.ArgumentParser:
    """The sub-command ``name`` (one-line help ``short``) run by ``func``; with ``scenario``, its
    SCENARIO argument and ``--set`` overrides. (``--json`` and -q/-v come last, from
    :func:`_decorate`.)"""
    p = sub.add_parser(name, help=short)
    p.set_defaults(func=func)
    if not scenario:
        return p
    p.add_argument(
        "scenario",
        metavar="SCENARIO",
        help="built-in scenario name (see `formation-ftc list`) or path to a TOML file",
    )
    p.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="PATH=VALUE",
        help="override a field, e.g. --set simulation.horizon=100 (repeatable)",
    )
    return p


def _scenario_table(text: str) -> str:
    """Only the ``[scenario]`` table of a scenario file (``list`` needs its description; parsing the
    whole files of every scenario would cost most of the command's time): from its header line to
    the next line that starts a table."""
    table = re.search(r"^[ \t]*\[scenario\][ \t]*$.*?(?=^[ \t]*\[|\Z)", text, re.M | re.S)
    return text if table is None else table.group()  # unusual layout: parse everything


def _cmd_list(args) -> int:
    import tomllib
    from importlib import resources

    d = resources.files("formation_ftc") / "scenarios"
    rows = []
    for name in _resource_names("scenarios"):
        text = (d / f"{name}.toml").read_text(encoding="utf-8")
        meta = tomllib.loads(_scenario_table(text)).get("scenario", {})
        method = meta.get("method", "composed")
        rows.append(
            {
                "name": name,
                "method": str(method),
                "paper": meta.get("paper"),
                "description": str(meta.get("description", "")),
                "composed": method == "composed",
            }
        )
    if args.json:
        print_json({"scenarios": rows})
        return 0
    width = max((len(r["name"]) for r in rows), default=10)
    # the papers' reproductions first (grouped by paper), then every other scenario
    groups: dict[str, list[dict]] = {}
    for r in rows:
        groups.setdefault(r["paper"] or "", []).append(r)
    for k, paper in enumerate(sorted(groups, key=lambda p: (not p, p))):
        if k:
            print()
        print(f"{paper}:" if paper else "Other scenarios (compositions across papers, examples):")
        for r in groups[paper]:
            print(f"  {r['name']:<{width}}  {r['description']}")
    return 0


def _described_fields(data, schema: dict, is_table) -> list[tuple[str, Any, str]]:
    """``(dotted path, value, description)`` of every field of ``data`` (a scenario: a dict or a
    tomlkit document) that ``schema`` (its method's JSON Schema) knows; tables (``is_table(value)``)
    are entered, lists of tables are not; the description is "" where the schema gives none."""
    from formation_ftc.suggest import _resolve

    found: list[tuple[str, Any, str]] = []

    def walk(container, node: dict, prefix: str) -> None:
        props: dict = {}
        for option in _resolve(node, schema):
            props.update(option.get("properties", {}))
        for key, value in container.items():
            sub = props.get(key)
            if sub is None:
                continue
            if is_table(value):
                walk(value, sub, f"{prefix}{key}.")
                continue
            options = [sub, *_resolve(sub, schema)]
            desc = next((o.get("description") for o in options if o.get("description")), "")
            found.append((f"{prefix}{key}", value, " ".join(str(desc).split())))

    walk(data, schema, "")
    return found


#: characters of a line of ``show``'s TOML an array is kept within (one line when it fits)
_TOML_WIDTH = 100


def _toml_value(value: Any, indent: str = "", room: int = _TOML_WIDTH) -> str:
    """TOML text of ``value`` as a person writes it: an array on one line when it fits in ``room``
    characters (``[1.0, 2.0]``, ``[[1, 0], [0, 1]]``), else one element per line, indented, with
    numbers as many to a line as fit; scalars and inline tables as tomli_w writes them."""
    import textwrap

    import tomli_w

    if isinstance(value, dict):
        items = ", ".join(
            f"{_toml_key(k)} = {_toml_value(v, room=10**9)}" for k, v in value.items()
        )
        return "{ " + items + " }" if value else "{}"
    if not isinstance(value, list):
        return tomli_w.dumps({"x": value})[len("x = ") : -1]
    one_line = "[" + ", ".join(_toml_value(v, room=10**9) for v in value) + "]"
    if len(one_line) <= room or not value:
        return one_line
    inner = indent + "    "
    width = _TOML_WIDTH - len(inner)
    if all(isinstance(v, int | float) for v in value):  # numbers (and booleans): fill the lines
        words = " ".join(_toml_value(v) + "," for v in value)
        lines = textwrap.wrap(words, width, break_long_words=False, break_on_hyphens=False)
    else:  # strings, arrays, tables: one to a line
        lines = [_toml_value(v, inner, width - 1) + "," for v in value]
    return "[\n" + "".join(f"{inner}{line}\n" for line in lines) + indent + "]"


def _toml_key(key: str) -> str:
    import tomli_w

    return tomli_w.dumps({key: 0})[: -len(" = 0\n")]


def _readable_toml(text: str) -> str:
    """``text`` (TOML, as tomli_w writes it: every array one element per line) with every array
    written by :func:`_toml_value`; tables, keys and values are unchanged."""
    import tomlkit
    from tomlkit.items import AoT, Array, Table

    def walk(container) -> None:
        for key, item in list(container.items()):
            if isinstance(item, Table):
                walk(item)
            elif isinstance(item, AoT):
                for table in item:
                    walk(table)
            elif isinstance(item, Array):
                head = len(_toml_key(key)) + len(" = ")
                formatted = _toml_value(item.unwrap(), room=_TOML_WIDTH - head)
                container[key] = tomlkit.parse(f"x = {formatted}")["x"]

    doc = tomlkit.parse(text)
    walk(doc)
    return tomlkit.dumps(doc)


def _annotate_toml(text: str, schema: dict) -> str:
    """``text`` (TOML of a scenario) with each field's unit and meaning from ``schema`` as a trailing
    comment (``kp = 2.0  # [N/m] Position gain.``); the values are unchanged."""
    import tomlkit

    doc = tomlkit.parse(text)
    for _, item, desc in _described_fields(
        doc, schema, lambda v: isinstance(v, tomlkit.items.Table)
    ):
        if desc and hasattr(item, "comment"):
            item.comment(desc if len(desc) <= 100 else desc[:97] + "...")
    return tomlkit.dumps(doc)


_UNIT_WORD = re.compile(r"\b(?:kg|rad|deg|Hz|m|s|N|J|W|g)\b")


def _description_unit(desc: str) -> str | None:
    """The unit a field's description states in brackets (``"Position gain [N/m]."`` -> ``"N/m"``,
    ``[-]`` -> ``"1"``); None when it states none, or several different ones (``"... [rad], in t [s]"``)."""
    found = []
    for text in re.findall(r"\[([^\[\]]+)\]", desc):
        text = text.strip()
        if text == "-":
            found.append("1")
        elif _UNIT_WORD.search(text) and not re.sub(
            r"[\s/^*()\d,.-]", "", _UNIT_WORD.sub("", text)
        ):
            found.append(text)
    return found[0] if len(set(found)) == 1 else None


def _field_units(resolved: dict, schema: dict) -> dict[str, str]:
    """``{"controller.kp": "N/m", ...}``: the unit of every field of ``resolved`` (a scenario) whose
    description in ``schema`` (its method's JSON Schema) states one (lists of tables are not entered)."""
    units = {
        path: _description_unit(desc)
        for path, _, desc in _described_fields(resolved, schema, lambda v: isinstance(v, dict))
    }
    return {path: unit for path, unit in units.items() if unit is not None}


def _cmd_show(args) -> int:
    from formation_ftc.config.loader import dump_toml

    scenario = _load(args, build=False)  # fields only: `check` also builds the loop
    if args.json:  # the content of the TOML below, and the unit of each field that states one
        resolved = scenario.model_dump(mode="json", exclude_none=True)
        print_json(
            {"scenario": resolved, "units": _field_units(resolved, _scenario_schema(resolved))}
        )
        return 0
    text = _readable_toml(dump_toml(scenario))
    if not args.no_comments:
        text = _annotate_toml(text, _scenario_schema(scenario.model_dump(mode="json")))
    print(text, end="")
    return 0


def _cmd_check(args) -> int:
    from formation_ftc.api import check

    scenario = _load(args)
    failed = "the conditions cannot be evaluated for these values ({kind}: {exc})"
    conds = _as_scenario_error(check, scenario, args, failed)
    failed_required = [c for c in conds if c.required and c.holds is False]
    unproven_required = [c for c in conds if c.required and c.holds is None]
    code = 1 if failed_required else 0
    if args.json:
        from formation_ftc.condition_json import condition_json

        print_json(
            {
                "scenario": scenario.scenario.name,
                "method": scenario.scenario.method,
                "conditions": [condition_json(c) for c in conds],
                "all_required_hold": not failed_required,
                "required_failed": len(failed_required),
                "required_unproven": len(unproven_required),
                "exit_code": code,
            }
        )
        return code
    from formation_ftc.display import CONDITION_COLUMNS, condition_row, text_table

    rows = [[v if isinstance(v, str) else v[0] for v in condition_row(c)] for c in conds]
    if not sys.stdout.isatty():
        for line in text_table(CONDITION_COLUMNS, rows) if conds else []:
            print(line)
    else:
        from rich.console import Console
        from rich.table import Table

        rich_table = Table(*CONDITION_COLUMNS, title="Conditions")
        marks = {"yes": "[green]yes[/]", "NO": "[red]NO[/]", "unproven": "[yellow]unproven[/]"}
        for r in rows:
            rich_table.add_row(*r[:4], marks.get(r[4], "n/a"), *r[5:])
        Console().print(rich_table)
    for c in conds:
        if c.detail and (c.holds is False or (c.required and c.holds is None)):
            print(f"- {c.name}: {c.detail}")
    if not conds:
        print("this scenario's method declares no conditions")
    else:
        print(
            f"{len(unproven_required)} required condition(s) unproven (not evaluated, or sampled / heuristic "
            "with no violation found)"
        )
    return code


def _as_scenario_error(fn, scenario, args, failed: str) -> Any:
    """``fn(scenario)``; a ValueError, TypeError, ArithmeticError or RecursionError it raises becomes a
    ScenarioError (bad input, exit status 2): ``args.scenario``, then ``failed`` formatted with
    ``exc`` and ``kind`` (its class name)."""
    from formation_ftc.config.loader import ScenarioError

    try:
        return fn(scenario)
    except (ValueError, TypeError, ArithmeticError, RecursionError) as exc:
        if isinstance(exc, ScenarioError):
            raise
        reason = failed.format(exc=exc, kind=type(exc).__name__)
        raise ScenarioError(f"{args.scenario}: {reason}") from None


def _cmd_schema(args) -> int:
    if args.method == "composed":  # every slot: a oneOf over the catalog's component types
        from formation_ftc.shipped_schema import composed_schema

        schema = composed_schema()  # the shipped copy while current: no catalog import (start-up)
    else:
        from formation_ftc.registry import methods
        from formation_ftc.suggest import did_you_mean

        registered = methods()
        if args.method is None:
            width = max((len(n) for n in registered), default=10)
            for name, m in sorted(registered.items()):
                print(f"{name:<{width}}  {m.description}")
            return 0
        if args.method not in registered:
            raise InputError(
                f"unknown method {args.method!r}{did_you_mean(args.method, registered)}; "
                f"registered: {', '.join(sorted(registered))}"
            )
        schema = registered[args.method].schema.model_json_schema()
    schema = {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": f"formation-ftc scenario ({args.method})",
        **{k: v for k, v in schema.items() if k != "title"},
    }
    print(json.dumps(schema, indent=2))
    return 0


def _moved(path, stage: Path, out_dir: Path) -> Path:
    """Where ``path``, written into the staging directory, lies once it replaced ``out_dir``."""
    try:
        return out_dir / Path(path).relative_to(stage)
    except ValueError:  # written elsewhere
        return Path(path)


def _finish(scenario, loop, out, console) -> tuple[Any, dict[str, float], dict | None]:
    """The dataset and metrics of a run, and its divergence (None, or the ``diverged`` object of
    ``run --json``; the dataset is then the partial result)."""
    from formation_ftc.api import finish_run, result_metrics
    from formation_ftc.sim.engine import SimulationDiverged

    try:
        ds, metrics = finish_run(scenario, loop, out)
        return ds, metrics, None
    except SimulationDiverged as exc:
        console.print(f"[red]{exc}[/]")
        info = exc.info
        return (
            exc.partial,
            result_metrics(exc.partial),
            {
                "message": str(exc),
                "time": float(info.time),
                "step": int(info.step),
                "variable": str(info.variable),
                "spacecraft": None if info.spacecraft is None else int(info.spacecraft) + 1,
                "index": [int(i) for i in info.index],
                "reason": str(info.reason),
                "units": {"time": "s"},
            },
        )


def _cmd_run(args) -> int:
    import jax
    from rich.console import Console

    from formation_ftc.api import build_loop, metric_units, save_result
    from formation_ftc.limits import Budgets, check_memory, check_run_steps
    from formation_ftc.report.run_page import run_figures, write_run_page
    from formation_ftc.runout import check_out_dir, staged_output
    from formation_ftc.sim.programs import jitted_run

    console = Console(stderr=True, quiet=_VERBOSITY < 0)
    out_dir = check_out_dir(args.out, force=args.force)  # before any computation
    scenario = _load(args)
    budgets = Budgets.resolve(args.max_memory, args.max_run_steps)
    check_run_steps(scenario.simulation.n_steps, budgets, args.scenario)
    loop = _as_scenario_error(build_loop, scenario, args, "the scenario cannot be compiled: {exc}")
    check_memory(loop, budgets, args.scenario)
    if _ONE_SHOT_PROCESS:  # what writing the result needs, imported while XLA runs without the GIL
        _import_in_background("xarray", "formation_ftc.provenance")
    t0 = time.perf_counter()
    with console.status(
        f"compiling and running {scenario.scenario.name} ({scenario.simulation.n_steps:,} steps)..."
    ):
        out = jitted_run(loop)(loop)
        jax.block_until_ready(out)
    simulation = time.perf_counter() - t0
    figs: list[Path] | None = None
    ds, metrics, diverged = _finish(scenario, loop, out, console)
    ds.attrs["simulation_time_s"] = simulation  # compiling (or loading) and running [s]
    units = metric_units(ds)
    with staged_output(out_dir) as stage:  # replaces out_dir only once everything is written
        save_result(ds, stage, metrics)
        if args.figures:
            figs, note = run_figures(ds, scenario, stage)
            if note:
                console.print(note)
        write_run_page(stage, ds, metrics, figs, units)
    code = 0 if diverged is None else 1
    wall = time.perf_counter() - _STARTED  # since this command began (main) [s]
    drawn = f", index.html and {len(figs)} figure(s)" if figs is not None else " and index.html"
    hint = "" if figs is not None else f"; figures: formation-ftc plot {out_dir}"
    console.print(
        f"wrote {out_dir}/result.nc, metrics.json{drawn} in {wall:.2f} s (simulation "
        f"{simulation:.2f} s){hint}",
        soft_wrap=True,
        markup=False,
        highlight=False,
    )
    if args.json:
        print_json(
            {
                "scenario": scenario.scenario.name,
                "method": scenario.scenario.method,
                "exit_code": code,
                "diverged": diverged,
                "metrics": {
                    k: {"value": v, "units": units.get(k, "1")} for k, v in metrics.items()
                },
                "outputs": {
                    "dir": str(out_dir),
                    "result": str(out_dir / "result.nc"),
                    "metrics": str(out_dir / "metrics.json"),
                    "index": str(out_dir / "index.html"),
                    "figures": [str(_moved(f, stage, out_dir)) for f in figs or []],
                },
                "n_steps": int(scenario.simulation.n_steps),
                "wall_time": wall,
                "simulation_time": simulation,
                "units": {"wall_time": "s", "simulation_time": "s"},
            }
        )
    return code


def _cmd_plot(args) -> int:
    d = Path(args.dir)
    if (d / "result.nc").is_file():
        from formation_ftc.report.run_page import redraw_run

        figures, index, warnings = redraw_run(d, args.format)
        kind: str = "run"
    elif (d / "manifest.json").is_file():  # formation_ftc.campaign.storage.MANIFEST
        from formation_ftc.campaign.report import write_report
        from formation_ftc.plotting import figure_format

        with figure_format(args.format):
            _, figures = write_report(d, console=None, plots=True)
        index, warnings, kind = None, [], "campaign"
    elif (d / "league.json").is_file():  # formation_ftc.league.runner.LEAGUE_FILE
        from formation_ftc.league.report import write_leaderboard

        if args.format != "png":
            raise InputError(
                f"--format {args.format}: a league's leaderboard page embeds PNG figures; "
                "use --format png (the default) for a league directory"
            )
        write_leaderboard(d, plots=True)
        figures = sorted((d / "leaderboard").glob("*.png"))
        index, warnings, kind = d / "leaderboard" / "index.html", [], "league"
    else:
        what = "does not exist" if not d.exists() else "is not a directory"
        if d.is_dir():
            what = "holds none of result.nc (a run), manifest.json (a campaign), league.json (a league)"
        raise InputError(
            f"plot {args.dir}: {what}; give the --out directory of a run, campaign or league"
        )
    for w in warnings if _VERBOSITY >= 0 else []:  # -q: no informational lines
        print(f"warning: {w}", file=sys.stderr)
    if args.json:
        print_json(
            {
                "dir": str(d),
                "kind": kind,
                "format": args.format,
                "figures": [str(f) for f in figures],
                "index": None if index is None else str(index),
                "warnings": warnings,
            }
        )
    else:
        where = f" and {index}" if index is not None else ""
        print(f"wrote {len(figures)} figure(s) of the {kind} in {d}{where}")
    return 0


class _VersionAction(argparse.Action):
    """``--version``: reads the package metadata only when asked (not for every command)."""

    def __init__(
        self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None
    ):
        help = help or "show the version and exit"
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        import formation_ftc

        print(f"formation-ftc {formation_ftc.__version__}")
        parser.exit()


def _add_verbosity(p: argparse.ArgumentParser, top: bool = False) -> None:
    g = p.add_mutually_exclusive_group()
    # a sub-command's flag must not reset the top-level one
    default = 0 if top else argparse.SUPPRESS
    for flag, const, text in (
        ("quiet", -1, "print only results and errors (no progress or informational lines)"),
        ("verbose", 1, "more detail (timings, full tracebacks on errors)"),
    ):
        g.add_argument(
            f"-{flag[0]}",
            f"--{flag}",
            dest="verbosity",
            action="store_const",
            const=const,
            default=default,
            help=text,
        )


def _parsers(parser: argparse.ArgumentParser, key: str = ""):
    """``(command path, parser)`` of ``parser`` ("") and of every sub-command ("league run"), each
    parser before its sub-commands."""
    yield key, parser
    for action in parser._actions:  # noqa: SLF001 - argparse keeps sub-parsers here
        if isinstance(action, argparse._SubParsersAction):  # noqa: SLF001
            for name, sub in action.choices.items():
                yield from _parsers(sub, f"{key} {name}".strip())


#: the commands of this module that print results: their --json comes after their other options
_JSON_HERE = frozenset({"list", "show", "check", "run", "plot"})


def _decorate(parser: argparse.ArgumentParser) -> None:
    """Plain-text help with examples and exit codes on ``parser`` and every sub-command, ``--json`` on
    :data:`_JSON_HERE` and -q/-v on every sub-command."""
    for key, p in _parsers(parser):
        if key in _JSON_HERE:
            add_json_option(p)
        if key:
            _add_verbosity(p)
        p.formatter_class = argparse.RawDescriptionHelpFormatter
        p.description, examples = HELP.get(key, (p.description, []))
        lines = ["examples:", *(f"  {e}" for e in examples), ""] if examples else []
        p.epilog = "\n".join([*lines, EXIT_CODES])


#: commands whose parsers live in other modules: name -> (formation_ftc.MODULE with add_cli,
#: one-line help)
_PLUGGED = {
    "reproduce": ("report.reproduce", "reproduce the papers' studies and write an HTML report"),
    "campaign": ("campaign.cli", "Monte Carlo campaigns: list, run (resumable), report"),
    "league": ("league.cli", "FTC league: every method on one realistic formation, same faults"),
    "tune": (
        "league.tune_cli",
        "choose a league method's gains for a level, reported on held-out seeds",
    ),
    "falsify": (
        "league.falsify_cli",
        "search a league method's faults, initial errors and noise for a violating run",
    ),
}


class _Parser(argparse.ArgumentParser):
    """An argument parser whose usage errors (exit status 2) carry their message, for ``--json``
    (the sub-command parsers are of the same class)."""

    def error(self, message: str) -> NoReturn:
        try:
            super().error(message)
        except SystemExit as exc:
            exc.usage_error = f"{self.prog}: {message}"  # type: ignore[attr-defined]
            raise


# ------------------------------------------------------------------------------------ completion
_SHELLS = ("bash", "zsh", "tcsh")


def _resource_names(folder: str, prefix: str = "", suffix: str = ".toml") -> list[str]:
    """Names of the package's files ``folder/PREFIX*SUFFIX`` (without prefix and suffix), found
    without importing the modules that use them."""
    from importlib import resources

    d = resources.files("formation_ftc") / folder
    try:
        names = sorted(e.name for e in d.iterdir())
    except (OSError, FileNotFoundError):  # pragma: no cover - a damaged installation
        return []
    return [
        n[len(prefix) : len(n) - len(suffix)]
        for n in names
        if n.startswith(prefix) and n.endswith(suffix)
    ]


def _paper_names() -> list[str]:
    """The built-in paper packages (formation_ftc/papers/NAME/), without importing them."""
    from importlib import resources

    d = resources.files("formation_ftc") / "papers"
    return sorted(e.name for e in d.iterdir() if e.is_dir() and (e / "__init__.py").is_file())


def _names_completer(kind: str, names: list[str], files: bool) -> dict[str, Any]:
    """shtab completion of a positional taking a built-in ``kind`` name (or, with ``files``, a TOML
    file): bash and zsh functions in the script's preamble, a word list for tcsh."""
    words = " ".join(names)
    fn = f"_formation_ftc_{kind}{'_or_file' if files else ''}"  # "_file": bash completes file names
    bash = [f"{fn}() {{", f'  compgen -W "{words}" -- "$1"']
    zsh = f"{fn}() {{\n  _alternative 'names:built-in {kind}:({words})'"
    if files:
        bash += ["  compgen -f -X '!*.toml' -- \"$1\"", '  compgen -d -- "$1"']
        zsh += " 'files:TOML file:_files -g \"*.toml\"'"
    return {
        "bash": fn,
        "zsh": fn,
        "tcsh": f"({words})",
        "preamble": {"bash": "\n".join([*bash, "}"]), "zsh": zsh + "\n}"},
    }


def _add_completion_hints(parser: argparse.ArgumentParser) -> None:
    """Completions of argument values: built-in scenario, campaign, league and paper names (or TOML
    files) for the positionals that take them, directories for --out and DIR arguments."""
    import shtab

    scenarios = _names_completer("scenario", _resource_names("scenarios"), files=True)
    by_command = {
        "reproduce": {"paper": _names_completer("paper", [*_paper_names(), "all"], files=False)},
        "campaign run": {
            "campaign": _names_completer("campaign", _resource_names("campaign/builtin"), True)
        },
        "league run": {
            "league": _names_completer("league", _resource_names("league/data", "league-"), True)
        },
    }

    for key, p in _parsers(parser):
        for action in p._actions:  # noqa: SLF001 - argparse keeps them here
            hint = by_command.get(key, {}).get(action.dest)
            if hint is None and action.dest == "scenario":
                hint = scenarios
            if hint is None and (action.dest in ("out", "dir") or action.metavar == "DIR"):
                hint = shtab.DIRECTORY
            if hint is not None:
                action.complete = hint  # type: ignore[attr-defined]  # read by shtab


def completion_parser() -> argparse.ArgumentParser:
    """The full ``formation-ftc`` parser with completion hints, built without importing JAX."""
    parser = build_parser("", completion=True)
    _add_completion_hints(parser)
    return parser


def _cmd_completion(args) -> int:
    import shtab

    print(shtab.complete(completion_parser(), shell=args.shell), end="")
    return 0


def _command_of(argv: list[str]) -> str | None:
    """The sub-command named in ``argv`` (top-level options are all flags), or None."""
    return next((a for a in argv if not a.startswith("-")), None)


def build_parser(command: str | None = "", *, completion: bool = False) -> argparse.ArgumentParser:
    """The ``formation-ftc`` parser.

    ``command`` = "" (default) builds every sub-command; a command name (or None: no command) builds
    the modules of that command only (the others get a placeholder with their one-line help), so
    that ``--help``, ``--version`` and ``list`` import no JAX, SciPy or pandas. ``completion``: every
    sub-command, a command whose module imports JAX (``reproduce``) with its arguments but not its
    handler (:func:`completion_parser`).
    """
    from formation_ftc.cli_options import add_budget_options, add_reproduce_parser

    parser = _Parser(prog="formation-ftc")
    parser.add_argument("--version", action=_VersionAction)
    _add_verbosity(parser, top=True)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    _command(sub, "list", _cmd_list, "list the built-in scenarios")
    p = _command(sub, "show", _cmd_show, "print the resolved TOML of a scenario", scenario=True)
    p.add_argument(
        "--no-comments",
        action="store_true",
        help="bare TOML (default: each field's unit and meaning as a comment)",
    )
    short = "evaluate the scenario's stability/design conditions"
    _command(sub, "check", _cmd_check, short, scenario=True)

    p = _command(sub, "schema", _cmd_schema, "print the JSON Schema of a method's scenario file")
    p.add_argument(
        "method",
        metavar="METHOD",
        nargs="?",
        help="method name (the [scenario].method of a scenario file); omit to list them",
    )

    short = "simulate a scenario and write result.nc, metrics.json, index.html"
    p = _command(sub, "run", _cmd_run, short, scenario=True)
    p.add_argument("--out", required=True, metavar="DIR", help="output directory")
    p.add_argument(
        "--force",
        action="store_true",
        help="replace DIR even when it is not empty and not an earlier run's result",
    )
    add_budget_options(p, batch="the run")
    p.add_argument(
        "--figures",
        action="store_true",
        help="also draw the standard and the method's figures (PNG) and the 3-D view; without it, "
        "`formation-ftc plot DIR` draws them later from result.nc",
    )

    p = _command(sub, "plot", _cmd_plot, "draw the figures of a run, campaign or league directory")
    p.add_argument(
        "dir", metavar="DIR", help="the --out directory of a run, a campaign or a league"
    )
    p.add_argument(
        "--format",
        choices=("png", "svg", "pdf"),
        default="png",
        help="file format of the figures (default png; a league's page embeds png only)",
    )

    for name, (module, short) in _PLUGGED.items():
        if completion and name == "reproduce":  # its module imports JAX: its arguments alone
            add_reproduce_parser(sub, _paper_names())
            continue
        if command not in ("", name):
            sub.add_parser(name, help=short, add_help=False).add_argument(
                "rest", nargs=argparse.REMAINDER
            )
            continue
        try:
            mod = importlib.import_module(f"formation_ftc.{module}")
        except ImportError as exc:  # pragma: no cover - only while a part is missing
            print(f"warning: formation_ftc.{module} unavailable: {exc}", file=sys.stderr)
            continue
        mod.add_cli(sub)

    p = _command(
        sub, "completion", _cmd_completion, "print the shell completion script (bash, zsh, tcsh)"
    )
    p.add_argument(
        "shell", choices=_SHELLS, metavar="SHELL", help=f"the shell: {', '.join(_SHELLS)}"
    )
    _decorate(parser)
    return parser


def main(argv: list[str] | None = None) -> int:
    global _VERBOSITY, _STARTED, _ONE_SHOT_PROCESS
    _STARTED = time.perf_counter()
    argv_given = argv
    with lossy_stderr():
        argv = list(sys.argv[1:] if argv is None else argv)
        parser = build_parser(_command_of(argv))
        try:
            args = parser.parse_args(argv)
        except SystemExit as exc:  # a usage error (status 2): with --json, also as a JSON document
            message = getattr(exc, "usage_error", None)
            if message and "--json" in argv[: argv.index("--") if "--" in argv else len(argv)]:
                print_json_error(message, int(exc.code or 2))
            raise
        _VERBOSITY = int(getattr(args, "verbosity", 0))
        if argv_given is None and args.command in _ONE_SHOT:
            _ONE_SHOT_PROCESS = True
            _few_full_collections()
            if args.command in ("run", "plot"):
                _without_dask()
            if args.command == "check":  # most conditions compute with numpy and scipy
                from formation_ftc import _lazy_jax

                _lazy_jax.install()
        from formation_ftc.exitcodes import run_guarded
        from formation_ftc.sim import runtime

        runtime.configure()  # compilation caches and compiler tuning, for this command and its workers

        code = run_guarded(args.func, args, verbose=_VERBOSITY > 0)
        if argv_given is None:  # the process's own command (console script, python -m): it ends now
            _exit_soon()
        return code


#: commands that compute one thing and end (their process: see :func:`_few_full_collections`)
_ONE_SHOT = frozenset({"run", "check", "plot"})


def _few_full_collections() -> None:
    """Full garbage collections only after 1000 (not 10) collections of the middle generation: each
    walks every object left by the imports (JAX, xarray, pydantic: millions), and a ``run`` made five
    of them, 0.3 s of its 2.8 s (measured on 2 cores), for garbage it mostly does not have. The
    younger generations are collected as usual. Only for a process whose one short command this is
    (:data:`_ONE_SHOT`, ``main()`` called without ``argv``)."""
    import gc

    young, middle, _ = gc.get_threshold()
    gc.set_threshold(young, middle, 1000)


def _import_in_background(*modules: str) -> None:
    """Import ``modules`` in a daemon thread, while the main thread waits on XLA (which compiles and
    runs without holding the GIL): a warm ``run`` of a small scenario then no longer imports xarray and
    pandas (0.3 s) after its simulation. A failing import fails again, with its message, where the
    command imports the module itself."""
    import threading

    def work() -> None:
        for name in modules:
            try:
                __import__(name)
            except Exception:  # noqa: BLE001 - reported by the command's own import
                return

    threading.Thread(target=work, name="formation-ftc-imports", daemon=True).start()


def _without_dask() -> None:
    """This process runs as if dask were not installed (``None`` in ``sys.modules`` makes its import
    fail as for a missing package), when neither dask nor xarray is imported yet.

    A run's result and a saved result hold numpy arrays only, yet xarray imports dask, ``dask.array``
    and ``distributed`` (the ``dask`` extra) while it builds and writes a dataset, to ask whether an
    array is a dask array and which scheduler writes it: 0.3-0.5 s of a 2.6 s ``run`` on 2 cores. An
    install without the extra skips that; so does this. Only for the process of a ``run`` or ``plot``
    command (``main()`` called without ``argv``), which uses no dask."""
    if not any(name in sys.modules for name in ("xarray", "dask", "distributed")):
        for name in ("dask", "distributed"):
            sys.modules[name] = None  # type: ignore[assignment]  # "not installed" to the import system


def _exit_soon() -> None:
    """Let the interpreter's shutdown skip the garbage collector's passes over every object left
    (JAX's, xarray's, the modules'): they are freed with the process. Those passes took 0.4-0.6 s
    after a ``run``, time the user waited but no command could print (measured on 2 cores;
    ``benchmarks/cli.py``). Only for a process whose command this was (``main()`` called without
    ``argv``), never for a caller that goes on."""
    import gc

    gc.freeze()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
