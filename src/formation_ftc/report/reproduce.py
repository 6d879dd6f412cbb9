"""``formation-ftc reproduce PAPER|all --out DIR``: run the registered paper reproductions, write the report.

For every selected paper (see :data:`formation_ftc.registry.PAPER_MODULES` for the order) the
registered :class:`~formation_ftc.registry.Reproduction` runs into ``DIR/<paper>/`` under one rich
progress bar; its wall time is measured here (compilation included). A paper that raises is recorded
as a failed section (with its traceback) and the others still run; the exit status is then 1.

Files written::

    DIR/.formation-ftc-report     marker: DIR is a report (a later run may overwrite it)
    DIR/summary.json              one paper: its summary + "paper" + "metadata";
                                  several (or "all"): {paper: summary, ..., "metadata": {...}}
    DIR/index.html                self-contained page (see formation_ftc.report.html)
    DIR/<paper>/summary.json      the paper's summary + "paper"
    DIR/<paper>/report.json       rows, checks, figures, notes, seeds, errata, status, wall time
    DIR/<paper>/*.png             the paper's figures (written by the reproduction)
    DIR/<paper>/trajectory3d.json optional 3-D trajectory data for the interactive view

An existing, non-empty ``DIR`` without the marker is refused unless ``force``; an unknown paper name
raises :class:`ReproduceError` listing the valid ones. JSON files are strict JSON: non-finite floats
are written as the strings ``"nan"``, ``"inf"``, ``"-inf"``.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import math
import os
import shutil
import sys
import time
import traceback
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from formation_ftc import registry
from formation_ftc.atomic import atomic_write
from formation_ftc.exitcodes import print_json, print_json_error
from formation_ftc.progress import _Bars, _since
from formation_ftc.registry import PaperReport, Reproduction
from formation_ftc.report.metadata import provenance, utc_now
from formation_ftc.report.profile import DIGITS, PHASES, Profiler, format_breakdown
from formation_ftc.sim.runtime import schedulable_cpus as _schedulable_cpus

__all__ = [
    "MARKER_NAME",
    "REPORT_SCHEMA",
    "ReproduceError",
    "available_reproductions",
    "select_papers",
    "prepare_output",
    "reproduce",
    "paper_entry",
    "to_jsonable",
    "add_cli",
    "run_cli",
    "json_document",
]

#: Marker file that identifies a directory written by ``formation-ftc reproduce``.
MARKER_NAME = ".formation-ftc-report"
#: Schema tag stored in every ``report.json``.
REPORT_SCHEMA = "formation-ftc-paper-report/1"

VERDICTS = ("match", "differs", "not stated")


class ReproduceError(Exception):
    """Bad input to ``reproduce`` (unknown paper, refused output directory); CLI exit status 2."""


# ----------------------------------------------------------------------------------------------- JSON
def to_jsonable(obj: Any) -> Any:
    """Convert ``obj`` to plain JSON types (numpy/JAX arrays and scalars, paths, dataclasses, sets).

    Non-finite floats become the strings ``"nan"``, ``"inf"``, ``"-inf"`` so the output is strict
    JSON (readable by browsers' ``JSON.parse``).
    """
    if obj is None or isinstance(obj, str | int):  # bool is an int
        return obj
    if isinstance(obj, float):
        if math.isfinite(obj):
            return obj
        return "nan" if math.isnan(obj) else ("inf" if obj > 0 else "-inf")
    if isinstance(obj, Mapping):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, Path):
        return str(obj)
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        as_dict = getattr(obj, "as_dict", None)
        return to_jsonable(as_dict() if callable(as_dict) else dataclasses.asdict(obj))
    if isinstance(obj, list | tuple):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, set | frozenset):
        return [to_jsonable(v) for v in sorted(obj, key=str)]
    if hasattr(obj, "__array__") or type(obj).__module__.startswith("numpy"):
        import numpy as np

        arr = np.asarray(obj)
        if arr.dtype.kind in "biuf":
            return to_jsonable(arr.tolist())
        if arr.dtype.kind == "c":
            return to_jsonable({"real": arr.real.tolist(), "imag": arr.imag.tolist()})
        return to_jsonable(arr.astype(str).tolist())
    if hasattr(obj, "item"):  # other scalar types exposing .item()
        with contextlib.suppress(Exception):
            return to_jsonable(obj.item())
    return str(obj)


def _write_json(path: Path, data: Any) -> None:
    """Write strict JSON atomically (temporary file then rename)."""
    atomic_write(path, json.dumps(to_jsonable(data), indent=2, allow_nan=False) + "\n")


# ------------------------------------------------------------------------------------- registry side
def available_reproductions() -> tuple[dict[str, Reproduction], dict[str, str]]:
    """Registered reproductions (report order) and the paper packages that failed to import.

    Returns ``(reproductions, import_failures)`` with ``import_failures = {paper: traceback}``. A
    paper package that raises on import does not hide the others: each built-in package is imported
    on its own first, so the report can show the broken one as a failed section.
    """
    found = registry.reproductions()  # load_plugins records failing imports instead of raising
    failures = {m.rsplit(".", 1)[-1]: tb for m, tb in registry.PLUGIN_ERRORS.items()}
    if "methods" in failures:
        print(
            "warning: formation_ftc.methods failed to import:\n" + failures.pop("methods"),
            file=sys.stderr,
        )
    return found, {p: tb for p, tb in failures.items() if p not in found}


def select_papers(requested: Iterable[str], valid: Iterable[str]) -> list[str]:
    """Resolve the requested names (``"all"`` or paper names) against ``valid``, keeping its order.

    Raises :class:`ReproduceError` naming the valid choices for an unknown name or an empty request.
    """
    requested = [str(r).strip() for r in requested]
    valid = list(valid)
    choices = ", ".join(valid + ["all"]) if valid else "none registered"
    if not requested:
        raise ReproduceError(f"no paper given; valid: {choices}")
    unknown = [r for r in requested if r != "all" and r not in valid]
    if unknown:
        raise ReproduceError(f"unknown paper {unknown[0]!r}; valid: {choices}")
    if "all" in requested:
        if not valid:
            raise ReproduceError("no paper reproduction is registered")
        return valid
    return [p for p in valid if p in requested]


def prepare_output(out: Path, force: bool = False) -> bool:
    """Create (or accept) the report directory and write the marker.

    Returns True when ``out`` held a previous report (then stale per-paper directories may be
    cleared). Raises :class:`ReproduceError` when ``out`` is a file, or an existing non-empty
    directory without the marker and ``force`` is False.
    """
    out = Path(out)
    previous = False
    if out.exists():
        if not out.is_dir():
            raise ReproduceError(f"--out {out} exists and is not a directory")
        previous = (out / MARKER_NAME).is_file()
        if not previous and any(out.iterdir()) and not force:
            raise ReproduceError(
                f"--out {out} exists, is not empty and is not a previous formation-ftc report "
                f"(no {MARKER_NAME} file); choose a new directory or pass --force to write into it"
            )
    out.mkdir(parents=True, exist_ok=True)
    from formation_ftc import __version__

    _write_json(
        out / MARKER_NAME,
        {"tool": "formation-ftc reproduce", "version": __version__, "written_utc": utc_now()},
    )
    return previous


# ----------------------------------------------------------------------------------------- progress
class _Bar(_Bars):
    """One progress line over all papers; ``callback(i, paper)`` is the papers' ``progress``. Its
    clock counts from ``started`` (``time.perf_counter()``; default: now), as the total does."""

    def __init__(self, enabled: bool, n_papers: int, console=None, started: float | None = None):
        super().__init__(
            {"reproduce": {"total": float(n_papers), "message": ""}},
            _since(started),
            "{task.fields[message]}",
            percent=True,
            enabled=enabled and n_papers > 0,  # a disabled bar shows nothing
            console=console,
        )
        self.n = n_papers

    def update(self, completed: float, message: str) -> None:
        self.update_line("reproduce", completed=completed, message=message)

    def callback(self, index: int, paper: str) -> Callable[[float, str], None]:
        def progress(fraction: float = 0.0, message: str = "") -> None:
            f = _fraction(fraction, 1.0)
            self.update(index + f, f"{paper} ({index + 1}/{self.n}) {message}".rstrip())

        return progress


def _fraction(value: Any, top: float) -> float:
    """A reported progress fraction clamped to [0, ``top``]; 0 for a non-number or a non-finite one."""
    try:
        f = float(value)
    except (TypeError, ValueError):
        return 0.0
    return min(max(f, 0.0), top) if math.isfinite(f) else 0.0


# ------------------------------------------------------------------------------------------ entries
def _counts(rows: list[dict], checks: list[dict]) -> tuple[dict[str, int], dict[str, int]]:
    verdicts = {v: sum(1 for r in rows if r.get("verdict") == v) for v in VERDICTS}
    open_ = [c for c in checks if c.get("holds") is None]  # neither shown to hold nor to fail
    unproven = sum(1 for c in open_ if c.get("basis") in ("sampled", "heuristic"))
    checks_summary = {
        "hold": sum(1 for c in checks if c.get("holds") is True),
        "fail": sum(1 for c in checks if c.get("holds") is False),
        "unproven": unproven,
        "not evaluated": len(open_) - unproven,
        "required_failed": sum(
            1 for c in checks if c.get("holds") is False and c.get("required", True)
        ),
    }
    return verdicts, checks_summary


def paper_entry(
    reproduction: Reproduction | None,
    paper: str,
    paper_dir: Path,
    report: PaperReport | None,
    wall_time_s: float,
    error: str | None = None,
) -> dict[str, Any]:
    """The ``report.json`` content of one paper (also what :mod:`formation_ftc.report.html` renders)."""
    rep = report or PaperReport(paper, {})  # a failed paper reports nothing
    rows, checks = [r.as_dict() for r in rep.rows], [c.as_dict() for c in rep.checks]
    figures = [
        dict(
            path=str(f.path),
            number=str(f.number),
            caption=f.caption,
            exists=(paper_dir / f.path).is_file(),
        )
        for f in rep.figures
    ]
    warnings = [
        f"figure {f['number']}: file {f['path']} was not written"
        for f in figures
        if not f["exists"]
    ]
    if rep.paper != paper:
        warnings.append(f"the reproduction returned a report for {rep.paper!r}, expected {paper!r}")
    verdicts, checks_summary = _counts(rows, checks)
    traj = paper_dir / "trajectory3d.json"
    return {
        "schema": REPORT_SCHEMA,
        "paper": paper,
        "title": reproduction.title if reproduction else paper,
        "citation": reproduction.citation if reproduction else "",
        "description": reproduction.description if reproduction else "",
        "errata": [
            {"id": str(e[0]), "text": str(e[1])} for e in getattr(reproduction, "errata", [])
        ],
        "status": "ok" if error is None else "failed",
        "error": error,
        "wall_time_s": round(float(wall_time_s), 3),
        "rows": rows,
        "verdicts": verdicts,
        "checks": checks,
        "checks_summary": checks_summary,
        "figures": figures,
        "scenarios": list(rep.scenarios),
        "seeds": list(rep.seeds),
        "notes": list(rep.notes),
        "warnings": warnings,
        "trajectory3d": traj.name if traj.is_file() else None,
        "finished_utc": utc_now(),
    }


def _paper_summary(entry: dict, report: PaperReport | None) -> dict[str, Any]:
    if entry["status"] == "ok" and report is not None:
        return dict(report.summary)
    return {"status": "failed", "error": _last_line(entry["error"]) or "failed"}


def _last_line(text: str | None) -> str | None:
    """The last line of an error text (a traceback's exception line), None when it has none."""
    lines = (text or "").strip().splitlines()
    return lines[-1] if lines else None


def _run_one(
    rep: Reproduction | None,
    paper: str,
    paper_dir: Path,
    progress: Callable[[float, str], None],
    import_error: str | None,
    profile: bool,
) -> tuple[dict[str, Any], dict[str, Any], dict[str, float] | None]:
    """One paper: (report.json entry, summary, phase breakdown or None)."""
    profiler = Profiler() if profile else None
    t0 = time.perf_counter()
    report: PaperReport | None = None
    error = import_error
    if rep is not None:
        try:
            with profiler if profiler is not None else contextlib.nullcontext():
                result = rep.run(paper_dir, progress)
            if not isinstance(result, PaperReport):
                raise TypeError(
                    f"Reproduction {paper!r}.run returned {type(result).__name__}, "
                    "expected registry.PaperReport"
                )
            report = result
        except Exception:
            error = traceback.format_exc()
    wall = time.perf_counter() - t0
    if report is not None:
        report.wall_time_s = wall
    entry = paper_entry(rep, paper, paper_dir, report, wall, error)
    breakdown = profiler.breakdown() if profiler is not None else None
    return entry, to_jsonable(_paper_summary(entry, report)), breakdown


# ------------------------------------------------------------------------------------------- driver
def reproduce(
    papers: list[str] | str,
    out: Path | str,
    force: bool = False,
    progress: bool = True,
    *,
    include_3d: bool = True,
    available: Mapping[str, Reproduction] | None = None,
    console=None,
    profile: bool = False,
    leagues: list[Path | str] | None = None,
    workers: int | None = None,
    started: float | None = None,
) -> dict[str, Any]:
    """Run the selected paper reproductions into ``out`` and write the report.

    Parameters
    ----------
    papers : paper names, or ``["all"]`` (a single string is accepted too).
    out : report directory (created; see :func:`prepare_output` for the refusal rule).
    force : write into an existing non-empty directory that is not a previous report.
    progress : show one rich progress bar (on stderr).
    include_3d : embed the interactive 3-D trajectory views (needs plotly).
    available : reproductions to choose from (default: the registry); tests inject fakes here.
    console : rich console for the final wall-time table (default: stdout).
    profile : time each paper's phases (see :mod:`formation_ftc.report.profile`: compile, run, post,
        plot, report), print them as a second table and store them in the run metadata
        (``metadata["profile"]``, and one ``profile_<paper>`` line each for the HTML page).
    workers : papers computed side by side, each in its own worker process (spawn), the longest
        first. None: one per CPU core, at most one per paper; 1: one after the other in this process
        (always so for injected ``available`` reproductions, which a worker process could not import).
        The numbers do not depend on it: every paper is a deterministic function of its scenarios.
    started : ``time.perf_counter()`` when the caller's wait began (default: this call); the total
        wall time counts from it (the command line passes the start of the command).

    Returns
    -------
    dict with ``exit_code`` (0 all papers ran, 1 one failed), ``papers`` (``{paper: {status,
    wall_time_s, error}}``), ``reports`` (``{paper: what its report.json holds}``), ``summary`` (what
    ``summary.json`` holds), ``index`` (path of ``index.html``), ``out``, ``wall_time_s`` (from
    ``started`` until the report was written [s]) and, with ``profile``, ``profile`` (``{paper:
    {phase: seconds}}``).
    """
    t_start = time.perf_counter() if started is None else started
    from formation_ftc.report import html as html_report

    papers = [papers] if isinstance(papers, str) else papers
    found, import_failures = (
        available_reproductions() if available is None else (dict(available), {})
    )
    order = {p: k for k, p in enumerate(registry.PAPER_MODULES)}  # display order of the built-ins
    valid = list(found) + sorted(import_failures, key=lambda p: (order.get(p, len(order)), p))
    selected = select_papers(papers, valid)
    single = len(selected) == 1 and "all" not in papers
    out = Path(out)
    previous = prepare_output(out, force)

    breakdowns: dict[str, dict[str, float]] = {}
    # injected reproductions (tests) run in this process unless workers are asked for explicitly
    n_workers = (
        _paper_workers(workers, len(selected)) if (available is None or workers is not None) else 1
    )
    for paper in selected:
        paper_dir = out / paper
        if previous and paper_dir.is_dir():
            shutil.rmtree(paper_dir)  # stale figures of an earlier report
        paper_dir.mkdir(parents=True, exist_ok=True)
    done: dict[str, tuple[dict[str, Any], dict[str, Any]]] = {}  # paper -> (entry, summary)

    def finished(paper: str, entry: dict, summary: dict, breakdown: dict | None) -> None:
        t_report = time.perf_counter()
        done[paper] = entry, summary
        _write_json(out / paper / "report.json", entry)
        _write_json(out / paper / "summary.json", {**summary, "paper": paper})
        if breakdown is not None:
            b = dict(breakdown)
            writing = time.perf_counter() - t_report  # [s], counted in "report" and in "total"
            for k in ("report", "total"):
                b[k] = round(b.get(k, 0.0) + writing, DIGITS)
            breakdowns[paper] = b

    with _Bar(progress, len(selected), started=t_start) as bar:
        if n_workers > 1:
            _reproduce_in_workers(
                selected, out, n_workers, profile, bar, finished, found, import_failures
            )
        else:
            for i, paper in enumerate(selected):
                bar.update(i, f"{paper} ({i + 1}/{len(selected)})")
                rep, error = found.get(paper), import_failures.get(paper)
                entry, summary, breakdown = _run_one(
                    rep, paper, out / paper, bar.callback(i, paper), error, profile
                )
                finished(paper, entry, summary, breakdown)
                bar.update(i + 1, f"{paper} {entry['status']} in {entry['wall_time_s']:.1f} s")
    entries = [done[p][0] for p in selected]
    summaries = {p: done[p][1] for p in selected}
    papers_s = time.perf_counter() - t_start  # from the start of the wait to the last paper's end

    metadata: dict[str, Any] = {
        **provenance(),
        "command": "formation-ftc reproduce " + " ".join(papers),
        "papers": selected,
        **{k: {e["paper"]: e[k] for e in entries} for k in ("status", "wall_time_s", "seeds")},
        "total_wall_time_s": round(papers_s, 3),
        "paper_workers": n_workers,
    }
    if n_workers > 1:  # each worker's CPU-client threads (the compiled programs depend on it)
        metadata["paper_worker_cpu_threads"] = _worker_threads(n_workers)
    breakdowns = {p: breakdowns[p] for p in selected if p in breakdowns}
    if profile:
        metadata["profile_method"] = (
            "compile: JAX trace + MLIR lowering + XLA compile (incl. persistent-cache "
            "reads) from jax.monitoring time spans; run/plot: marked blocks without "
            "compile; post: the rest of the paper's wall time; report: JSON files"
        )
        if n_workers > 1:
            metadata["profile_method"] += (
                f"; papers ran side by side in {n_workers} worker processes, so the "
                "papers' times add up to more than the total wall time"
            )
        metadata["profile"] = breakdowns
        for p, b in breakdowns.items():
            metadata[f"profile_{p}"] = format_breakdown(b)
    summary_doc: dict[str, Any] = {**summaries, "metadata": metadata}
    if single:  # one paper: its summary at the top level
        summary_doc = {**summaries[selected[0]], "paper": selected[0], "metadata": metadata}
    t_index = time.perf_counter()
    _write_json(out / "summary.json", summary_doc)
    index = html_report.write_index(out, entries, metadata, include_3d=include_3d, leagues=leagues)
    index_s = time.perf_counter() - t_index

    total = time.perf_counter() - t_start  # the whole wait, report writing included
    _print_table(entries, total, index, console)
    if profile:
        _print_profile(breakdowns, index_s, console)
    result = {
        "exit_code": 1 if any(e["status"] != "ok" for e in entries) else 0,
        "papers": {
            e["paper"]: {k: e[k] for k in ("status", "wall_time_s", "error")} for e in entries
        },
        "reports": {e["paper"]: e for e in entries},
        "summary": to_jsonable(summary_doc),
        "index": str(index),
        "out": str(out),
        "wall_time_s": total,
    }
    if profile:
        result["profile"] = {**breakdowns, "index.html": {"report": round(index_s, DIGITS)}}
    return result


#: Relative cost of each built-in reproduction: wall seconds of a cold plus a warm compilation-cache
#: run, measured side by side on 2 cores (``benchmarks/reproduce.py``). Workers take the longest first,
#: so the last paper to start is a short one. Unknown papers count as long.
PAPER_COST = {
    "mehrabian": 53.0,
    "azizi2009": 47.0,
    "gui2022": 45.0,
    "li2020": 38.0,
    "yang2013": 5.0,
}


def _paper_workers(workers: int | None, n_papers: int) -> int:
    """Worker processes for ``n_papers`` papers (``workers`` None: one per CPU core, at most one per paper)."""
    if workers is not None:
        if workers < 1:
            raise ReproduceError(f"--workers must be >= 1, got {workers}")
        return min(workers, max(n_papers, 1))
    return max(1, min(_schedulable_cpus(), n_papers))


def _worker_threads(n_workers: int) -> str:
    """``PJRT_NPROC`` of each paper worker: the user's value when set, else the process's CPUs shared
    out among the workers (at least one). A simulation step is a chain of small operations; with more
    threads than cores XLA's hand-over between threads costs more CPU than it saves
    (``benchmarks/cpu_threads.py``)."""
    return os.environ.get("PJRT_NPROC") or str(max(1, _schedulable_cpus() // max(n_workers, 1)))


@contextlib.contextmanager
def _threads_for_workers(n_workers: int):
    """``PJRT_NPROC`` for the worker processes started inside the block (JAX reads it when a process's
    CPU client starts); a value the user set is kept."""
    if "PJRT_NPROC" in os.environ:
        yield
        return
    os.environ["PJRT_NPROC"] = _worker_threads(n_workers)
    try:
        yield
    finally:
        os.environ.pop("PJRT_NPROC", None)


def _paper_in_worker(
    rep: Reproduction | None,
    paper: str,
    paper_dir: str,
    import_error: str | None,
    profile: bool,
    messages,
) -> tuple[dict[str, Any], dict[str, Any], dict[str, float] | None]:
    """One paper in a worker process: (report.json entry, summary, phase breakdown or None).
    ``rep`` None: looked up by name in the worker's registry."""
    found: Mapping[str, Reproduction]
    failures: Mapping[str, str]
    found, failures = ({paper: rep}, {}) if rep is not None else available_reproductions()

    def progress(fraction: float = 0.0, message: str = "") -> None:
        with contextlib.suppress(Exception):  # progress is cosmetic; never fail a paper on it
            messages.put((paper, float(fraction), str(message)))

    rep = found.get(paper)
    error = import_error or failures.get(paper)
    if rep is None and error is None:
        error = f"no reproduction named {paper!r} in this worker process (available: {', '.join(found)})"
    return _run_one(rep, paper, Path(paper_dir), progress, error, profile)


def _shippable(rep: Reproduction | None) -> Reproduction | None:
    """``rep`` when it can be sent to a worker process (pickled), else None (the worker looks it up)."""
    import pickle

    try:
        pickle.dumps(rep)
    except Exception:  # noqa: BLE001 - closures, lambdas: the worker imports the registry instead
        return None
    return rep


def _reproduce_in_workers(
    selected: list[str],
    out: Path,
    n_workers: int,
    profile: bool,
    bar: _Bar,
    finished: Callable[..., None],
    found: Mapping[str, Reproduction],
    import_failures: Mapping[str, str],
) -> None:
    """Run the papers in a spawn process pool, the longest first; progress messages come back
    through a queue, read between waits for the papers; a worker that dies takes only its paper down
    (recorded as failed)."""
    import multiprocessing
    import queue as queue_module
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    ctx = multiprocessing.get_context("spawn")
    manager = ctx.Manager()
    messages = manager.Queue()
    order = sorted(selected, key=lambda p: -PAPER_COST.get(p, 100.0))
    running = dict.fromkeys(order, (0.0, ""))  # paper -> (fraction done, message), while it runs
    t0 = {p: time.perf_counter() for p in selected}
    try:
        with (
            _threads_for_workers(n_workers),
            ProcessPoolExecutor(max_workers=n_workers, mp_context=ctx) as pool,
        ):
            futures = {}
            for p in order:
                args = (_shippable(found.get(p)), p, str(out / p), import_failures.get(p))
                futures[pool.submit(_paper_in_worker, *args, profile, messages)] = p
            pending = set(futures)
            while pending:
                done, pending = wait(pending, timeout=0.2, return_when=FIRST_COMPLETED)
                with contextlib.suppress(queue_module.Empty, EOFError, OSError):
                    while True:
                        paper, fraction, message = messages.get_nowait()
                        if paper in running:
                            running[paper] = (_fraction(fraction, 0.999), message)
                for fut in done:
                    paper = futures[fut]
                    try:
                        entry, summary, breakdown = fut.result()
                    except Exception:  # the worker died (killed, out of memory): this paper failed
                        wall, error = time.perf_counter() - t0[paper], traceback.format_exc()
                        entry = paper_entry(None, paper, out / paper, None, wall, error)
                        summary, breakdown = _paper_summary(entry, None), None
                    finished(paper, entry, summary, breakdown)
                    del running[paper]
                n_done = len(selected) - len(running)
                fraction = n_done + sum(f for f, _ in running.values())
                text = " | ".join(f"{p} {m}".strip() for p, (_, m) in running.items())
                bar.update(fraction, f"{n_done}/{len(selected)} done  {text}")
    finally:
        manager.shutdown()


def _print_profile(
    breakdowns: Mapping[str, Mapping[str, float]], index_s: float, console=None
) -> None:
    """The ``--profile`` table: seconds per phase (rows: papers, then the index page and the total)."""
    console = console or Console()
    table = Table(title="formation-ftc reproduce --profile: wall time per phase [s]")
    table.add_column("paper")
    columns = (*PHASES, "total")
    for ph in columns:
        table.add_column(escape(ph), justify="right")
    for paper, b in breakdowns.items():
        table.add_row(paper, *(f"{b.get(ph, 0.0):.2f}" for ph in columns))
    table.add_row("index.html", *("" for _ in PHASES[:-1]), f"{index_s:.2f}", f"{index_s:.2f}")
    index = {"report": index_s, "total": index_s}  # the page's writing, after the papers
    sums = [sum(b.get(ph, 0.0) for b in breakdowns.values()) + index.get(ph, 0.0) for ph in columns]
    table.add_row("total", *(f"{s:.2f}" for s in sums), end_section=True)
    console.print(table)
    console.print(
        "compile = JAX tracing + lowering + XLA compile (jax.monitoring time spans, persistent-cache "
        "reads included); run / plot = the reproduction's marked blocks without compile; post = the "
        "rest (Python post-processing); report = JSON and HTML writing",
        highlight=False,
    )


def _print_table(entries: list[dict], total: float, index: Path, console=None) -> None:
    console = console or Console()
    table = Table("paper", "status", title="formation-ftc reproduce: wall time per paper")
    for col in (escape("wall time [s]"), *VERDICTS, "conditions hold/fail"):
        table.add_column(col, justify="right")
    for e in entries:
        status = "[green]ok[/]" if e["status"] == "ok" else "[red]FAILED[/]"
        v, c = e["verdicts"], e["checks_summary"]
        counts = [str(v[k]) for k in VERDICTS]
        table.add_row(
            e["paper"], status, f"{e['wall_time_s']:.1f}", *counts, f"{c['hold']}/{c['fail']}"
        )
    table.add_row("total", "", f"{total:.1f}", "", "", "", "", end_section=True)
    console.print(table)
    for e in entries:
        if e["status"] != "ok":
            console.print(
                f"[red]{e['paper']} failed:[/] {_last_line(e['error']) or ''} "
                f"(traceback in {e['paper']}/report.json)",
                highlight=False,
            )
    console.print(f"report: {index}", highlight=False)


# ----------------------------------------------------------------------------------------------- CLI
def add_cli(subparsers) -> argparse.ArgumentParser:
    """Add the ``reproduce`` subcommand to an ``argparse`` subparsers object (handler in ``func``).

    Its arguments come from :func:`formation_ftc.cli_options.add_reproduce_parser`, which the completion
    script (``formation-ftc completion``) uses without importing this module (JAX).
    """
    from formation_ftc.cli_options import add_reproduce_parser

    p = add_reproduce_parser(subparsers, registry.PAPER_MODULES)
    p.set_defaults(func=run_cli)
    return p


def run_cli(args: argparse.Namespace) -> int:
    """Handler of ``formation-ftc reproduce``; returns the exit status (0, 1 a paper failed, 2 bad input).

    With ``--json``: the tables go to stderr with the progress bar, and one JSON document
    (:func:`json_document`) to stdout at the end."""
    started = time.perf_counter()
    as_json = bool(getattr(args, "json", False))
    console = Console(stderr=True) if as_json else None
    try:
        # with --json, standard output carries the one document: anything printed meanwhile -> stderr
        with contextlib.redirect_stdout(sys.stderr) if as_json else contextlib.nullcontext():
            result = reproduce(
                args.paper,
                args.out,
                force=args.force,
                progress=True,
                include_3d=getattr(args, "include_3d", True),
                profile=getattr(args, "profile", False),
                leagues=getattr(args, "league", None),
                workers=getattr(args, "workers", None),
                console=console,
                started=started,
            )
    except ReproduceError as exc:
        print(f"error: {exc}", file=sys.stderr)
        if as_json:
            print_json_error(str(exc), 2)
        return 2
    if as_json:
        print_json(json_document(result))
    return int(result["exit_code"])


def _stated(text: str) -> dict[str, Any]:
    """A value of a comparison row as printed (``"9.8 s (Fig. 3)"``) with its number and unit when the
    text states exactly one outside parenthesised remarks (the parser of ``check --json``)."""
    from formation_ftc.condition_json import quantities as _quantities

    main = _quantities(text)[1] if text else []
    one = main[0] if len(main) == 1 else {"value": None, "units": None}
    return {"text": text, "value": one["value"], "units": one["units"]}


def _row_json(row: Mapping[str, Any]) -> dict[str, Any]:
    return {
        "quantity": row["quantity"],
        **{k: _stated(row[k]) for k in ("published", "reference", "ours")},
        "criterion": row["criterion"],
        "verdict": row["verdict"],
        "basis": [
            dict(zip(("relation", "lhs", "rhs", "tolerance"), clause, strict=False))
            for clause in row["basis"]
        ],
        "note": row["note"],
    }


def _paper_json(entry: Mapping[str, Any], out: Path) -> dict[str, Any]:
    from formation_ftc.condition_json import condition_json as _condition_json
    from formation_ftc.registry import Condition

    paper_dir = out / entry["paper"]
    return {
        "title": entry["title"],
        "status": entry["status"],
        "error": _last_line(entry["error"]),
        "verdicts": entry["verdicts"],
        "rows": [_row_json(r) for r in entry["rows"]],
        "conditions_summary": entry["checks_summary"],
        "conditions": [_condition_json(Condition(**c)) for c in entry["checks"]],
        "warnings": entry["warnings"],
        "wall_time": entry["wall_time_s"],
        "outputs": {
            "dir": str(paper_dir),
            "report": str(paper_dir / "report.json"),
            "summary": str(paper_dir / "summary.json"),
            "figures": [str(paper_dir / f["path"]) for f in entry["figures"] if f["exists"]],
        },
    }


def json_document(result: Mapping[str, Any]) -> dict[str, Any]:
    """The ``reproduce --json`` document (docs/cli.md) of what :func:`reproduce` returned."""
    out = Path(result["out"])
    papers = {p: _paper_json(e, out) for p, e in result["reports"].items()}
    return {
        "papers": papers,
        "verdicts": {v: sum(p["verdicts"][v] for p in papers.values()) for v in VERDICTS},
        "failed": [p for p, d in papers.items() if d["status"] != "ok"],
        "exit_code": result["exit_code"],
        "wall_time": result["wall_time_s"],
        "outputs": {
            "dir": str(out),
            "index": result["index"],
            "summary": str(out / "summary.json"),
        },
        "units": {"wall_time": "s"},
    }
