"""A paper's reproduction declared as data: ``papers/<paper>/study.toml`` names its runs, its figures,
its comparison rows, its notes and its summary; the paper's ``quantities`` function computes the numbers
they read. :func:`study` turns the two into the :class:`~formation_ftc.registry.Reproduction` that
``formation-ftc reproduce`` runs.

The file's tables (every text may name quantities as ``{name}``, ``{name:.4f}`` or ``{name[key]}``, the
:meth:`str.format` syntax):

``[reproduction]``
    ``paper``, ``title``, ``citation``, ``description``; ``runs`` (scenario names, or tables
    ``{name, scenario, set}``: scenario ``scenario`` with the dotted overrides ``set``, run as ``name``);
    ``batch`` (true: runs of one structure as one vmapped batch); ``check`` (scenario names whose
    conditions are reported, unless the quantities hold ``checks``); ``summary`` (quantity names, or
    ``{key = TEXT, value = NAME}``, copied into the report's summary, or the name of a quantity
    holding the whole summary); ``seeds``; ``notes`` (texts; one
    that fills to nothing is left out); ``errata`` (tables ``{id, text}``); ``constants`` (named values
    the quantities, texts and clauses use, e.g. reference values with their sources in comments, or
    the size of a sweep, which a caller may override).
``[[figures]]``
    ``file``, ``number``, ``caption``, ``draw`` (a function of the paper's ``figures`` module),
    ``args`` (passed before the output path: quantity names, ``"dataset:RUN"`` for a run's dataset,
    or tables of those), ``kwargs`` (literal keyword arguments),
    optional ``when`` (a quantity: the figure is drawn only when it is true) and ``listed = false`` (drawn,
    not listed among the report's figures, e.g. an interactive view); ``kwargs`` may instead name a
    quantity holding them, and the caption may name quantities.
``[[rows]]``
    ``quantity``, ``published`` (never filled), ``ours``, ``criterion``, ``note``, ``reference`` and ``basis``: the
    verdict's clauses ``[relation, lhs, rhs, tol]`` whose strings name quantities, or the name of a
    quantity holding the clauses (a row without a basis is "not stated"); optional ``when`` as for
    figures; ``for_each``: a quantity holding a list of tables, one row per table, its keys added to the
    quantities of that row (and then ``quantity`` and ``published`` are filled too).
"""

from __future__ import annotations

import functools
import importlib
import time
import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from formation_ftc.registry import ComparisonRow, Figure, PaperReport, Reproduction
from formation_ftc.report.profile import phase

__all__ = ["Run", "study", "run_study", "load_runs", "read_study"]


@dataclass(frozen=True)
class Run:
    """One simulated run of a study: its validated scenario, its dataset and its in-run metrics."""

    scenario: Any
    dataset: Any
    metrics: dict[str, float]
    compile_s: float = 0.0  # compiling its program here [s] (0 when the process had it)
    run_s: float = 0.0  # running it (its batch) [s]


def _text(template: str, q: dict[str, Any], where: str) -> str:
    try:
        return template.format(**q)
    except (KeyError, IndexError, ValueError) as exc:
        raise ValueError(f"{where}: {template!r} cannot be filled ({exc!r})") from None


def _value(x: Any, q: dict[str, Any], where: str) -> Any:
    """A clause's or an argument's value: a quantity's (a string names it), ``"dataset:RUN"`` the
    dataset of run RUN, a table with its values resolved so, or the literal itself."""
    if isinstance(x, dict):
        return {k: _value(v, q, where) for k, v in x.items()}
    if not isinstance(x, str):
        return x
    if x.startswith("dataset:") and x[8:] in q["runs"]:
        return q["runs"][x[8:]].dataset
    if x not in q:
        raise ValueError(f"{where}: no quantity {x!r} (known: {', '.join(sorted(q))})")
    return q[x]


def load_runs(
    spec: dict, overrides: dict | None = None, values: dict | None = None
) -> dict[str, Run]:
    """Load and simulate the ``runs`` of a study's ``[reproduction]`` table: ``overrides`` (dotted path
    -> value) apply to every run (e.g. a shorter horizon in tests); a ``set`` value ``"$name"`` is
    ``values[name]``. Runs with the same ``batch`` label (every run with ``batch = true`` on the
    table) run as vmapped batches, one per compiled structure; the others one by one, each timed."""
    from formation_ftc.api import load_scenario
    from formation_ftc.papers.programs import simulate_batched

    def value(v: Any) -> Any:
        return (values or {})[v[1:]] if isinstance(v, str) and v.startswith("$") else v

    scenarios: dict[str, Any] = {}
    groups: dict[tuple[bool, str], list[str]] = {}  # (batched, its label or the run) -> runs
    for entry in spec["runs"]:
        entry = {"name": entry} if isinstance(entry, str) else entry
        sets = {**(overrides or {}), **{k: value(v) for k, v in entry.get("set", {}).items()}}
        if "scenario" in entry:
            sets["scenario.name"] = entry["name"]
        scenarios[entry["name"]] = load_scenario(entry.get("scenario", entry["name"]), sets)
        label = entry.get("batch", "" if spec.get("batch", False) else None)
        key = (False, entry["name"]) if label is None else (True, label)
        groups.setdefault(key, []).append(entry["name"])
    runs: dict[str, Run] = {}
    with phase("run"):
        for (batched, _), names in groups.items():
            if batched:
                times: list = []
                out = simulate_batched([scenarios[n] for n in names], times)
                runs |= {
                    n: Run(scenarios[n], *o, *t) for n, o, t in zip(names, out, times, strict=True)
                }
            else:
                runs[names[0]] = _single(scenarios[names[0]])
    return {name: runs[name] for name in scenarios}


def _single(scenario: Any) -> Run:
    """One run through the process's shared executable of its structure, its times measured."""
    import jax

    from formation_ftc.api import build_loop, finish_run
    from formation_ftc.papers.programs import executable

    loop = build_loop(scenario)
    exe, compile_s = executable(loop)
    t0 = time.perf_counter()
    out = jax.block_until_ready(exe(loop))
    run_s = time.perf_counter() - t0
    ds, metrics = finish_run(scenario, loop, out)
    return Run(scenario, ds, metrics, compile_s, run_s)


def run_study(
    paper: str,
    quantities: Callable[[dict[str, Run], dict[str, Any]], dict[str, Any]],
    out_dir: Path,
    progress: Callable[[float, str], None] = lambda f, m: None,
    overrides: dict | None = None,
    data: dict | None = None,
    prepare: Callable[[dict[str, Any]], dict[str, Any]] | None = None,
) -> PaperReport:
    """Run ``paper``'s study: its runs, ``quantities(runs, constants)``, its figures into ``out_dir``
    and its rows (``data``: the study's tables; default ``papers/<paper>/study.toml``). ``overrides``:
    dotted paths -> values for every run's scenario (e.g. a shorter horizon in tests), and names of
    ``constants`` -> values (e.g. fewer seeds); the scenario overrides are also the constant
    ``overrides`` (for runs the quantities make themselves). ``prepare(constants)`` computes values
    before the runs (e.g. a design whose gain a run states), added to the constants."""
    from formation_ftc.api import check

    data = read_study(paper) if data is None else data
    spec = data["reproduction"]
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()
    progress(0.0, "simulating " + ", ".join(_names(spec)))
    over = overrides or {}
    constants = {**spec.get("constants", {}), **{k: v for k, v in over.items() if "." not in k}}
    constants |= prepare(constants) if prepare is not None else {}
    constants["overrides"] = {k: v for k, v in over.items() if "." in k}
    runs = load_runs(spec, constants["overrides"], constants)
    q = {**constants, **quantities(runs, constants), "runs": runs}
    progress(0.8, "figures")
    figures = []
    with phase("plot"):
        for f in data.get("figures", []):
            draw = importlib.import_module(f"formation_ftc.papers.{paper}.figures")
            if "when" in f and not _value(f["when"], q, f"figure {f['file']}"):
                continue
            args = [_value(a, q, f"figure {f['file']}") for a in f.get("args", [])]
            kwargs = f.get("kwargs", {})
            kwargs = _value(kwargs, q, f"figure {f['file']}") if isinstance(kwargs, str) else kwargs
            getattr(draw, f["draw"])(*args, out_dir / f["file"], **kwargs)
            if f.get("listed", True):
                caption = _text(f["caption"], q, f"figure {f['file']}")
                figures.append(Figure(f["file"], str(f["number"]), caption))
    rows = []
    for r in data.get("rows", []):
        items = _value(r["for_each"], q, f"row {r['quantity']!r}") if "for_each" in r else [None]
        for item in items:
            rows += _row(r, q if item is None else {**q, **item}, filled=item is not None)
    checks = q.get("checks") or [c for n in spec.get("check", []) for c in check(runs[n].scenario)]
    progress(1.0, "done")
    return PaperReport(
        paper=paper,
        summary=_summary(spec.get("summary", []), q),
        rows=rows,
        figures=figures,
        checks=checks,
        scenarios=list(q.get("scenarios", _names(spec))),
        seeds=list(q.get("seeds", spec.get("seeds", [0]))),
        notes=[t for n in spec.get("notes", []) if (t := _text(n, q, "note"))],
        wall_time_s=time.perf_counter() - t_start,
    )


def _row(r: dict, q: dict[str, Any], filled: bool) -> list[ComparisonRow]:
    """The comparison row of the table ``r`` (none when its ``when`` is false)."""
    where = f"row {r['quantity']!r}"
    if "when" in r and not _value(r["when"], q, where):
        return []
    keys = ("quantity", "published") * filled + ("ours", "criterion", "note", "reference")
    text = {**r, **{k: _text(r.get(k, ""), q, where) for k in keys}}
    common = (text["quantity"], text["published"], text["ours"], text["criterion"])
    if "basis" not in r:
        return [ComparisonRow(*common, "not stated", text["note"], text["reference"])]
    clauses = _value(r["basis"], q, where) if isinstance(r["basis"], str) else r["basis"]
    basis = tuple((c[0], *(_value(x, q, where) for x in c[1:])) for c in clauses)
    return [ComparisonRow.judged(*common, basis, text["note"], text["reference"])]


def _summary(entries: str | list, q: dict[str, Any]) -> dict[str, Any]:
    """The report's summary: the quantity named ``entries``, or one item per entry: a quantity's name
    (its key too), or ``{key = TEXT, value = NAME}``."""
    if isinstance(entries, str):
        return dict(_value(entries, q, "summary"))
    items = ({"key": e, "value": e} if isinstance(e, str) else e for e in entries)
    return {_text(e["key"], q, "summary"): _value(e["value"], q, "summary") for e in items}


def _names(spec: dict) -> list[str]:
    return [e if isinstance(e, str) else e["name"] for e in spec["runs"]]


def read_study(paper: str) -> dict:
    """The tables of ``papers/<paper>/study.toml``."""
    text = resources.files(f"formation_ftc.papers.{paper}").joinpath("study.toml").read_text()
    return tomllib.loads(text)


def study(
    paper: str,
    quantities: Callable[[dict[str, Run], dict[str, Any]], dict[str, Any]],
    prepare: Callable[[dict[str, Any]], dict[str, Any]] | None = None,
) -> Reproduction:
    """The :class:`~formation_ftc.registry.Reproduction` of ``papers/<paper>/study.toml`` whose
    numbers ``quantities`` computes from the runs."""
    spec = read_study(paper)["reproduction"]
    # run(out_dir, progress, overrides): the study's run with the paper's own arguments bound
    run = functools.partial(run_study, paper, quantities, prepare=prepare)
    return Reproduction(
        paper=paper,
        title=spec["title"],
        citation=spec["citation"],
        description=spec["description"],
        errata=[(e["id"], e["text"]) for e in spec.get("errata", [])],
        run=run,
    )
