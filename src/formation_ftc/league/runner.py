"""Run a league: one resumable campaign per method over every (fault case, actuator level) cell.

For each method the runner writes one full composed scenario per cell
(``DIR/<method>/cells/<case>--<level>.toml``, the exact input of those runs) and runs a campaign whose
grid axis is that list of scenarios and whose replicates are the Monte Carlo seeds. The replicates are
paired (common random numbers): replicate j has the same initial errors, fault onset and noise seed in
every cell and for every method, so differences between cells and between methods are not sampling
noise. Every cell of a method has the same structure, so one compiled program serves the whole method.

Everything is checked before the first run (unknown method or fault, a method that cannot drive the
league plant, metrics): a bad league fails with exit code 2 and writes nothing.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from formation_ftc.league.definition import (
    LeagueError,
    LeagueSpec,
    MethodEntry,
    league_hash,
    load_league,
    method_scenario,
)

__all__ = ["Cell", "LeagueOutcome", "plan_cells", "run_league", "load_league_results", "LEAGUE_FILE"]

LEAGUE_FILE = "league.json"


@dataclass(frozen=True)
class Cell:
    method: str
    case: str
    fault_kind: str
    level: str
    raw: dict  # the full composed scenario

    @property
    def key(self) -> str:
        return f"{self.case}--{self.level}"


@dataclass
class LeagueOutcome:
    out_dir: Path
    n_runs: int
    n_failed: int
    seconds: float
    per_method: dict[str, float]

    def __str__(self) -> str:
        return (f"{self.n_runs} runs ({self.n_failed} failed or diverged) in {self.out_dir} in {self.seconds:.1f} s")


def _battery(spec: LeagueSpec):
    from formation_ftc.league.battery import load_battery

    try:
        return load_battery(spec.league.battery)
    except ValueError as exc:
        raise LeagueError(f"league.battery = {spec.league.battery!r}: {exc}") from None


def plan_cells(spec: LeagueSpec, methods: list[str] | None = None) -> dict[str, list[Cell]]:
    """Every method's cells, each scenario validated (composition included) before anything runs.

    A case applies to a method when it means something for it (a communication fault needs a network,
    larger delays a delayed one). Every cell of a networked method uses the link-fault network (with no
    lost link outside the communication cases), so all its cells share one compiled program."""
    from formation_ftc.api import load_scenario

    battery = _battery(spec)
    chosen = [spec.method(m) for m in methods] if methods else spec.methods
    quantity = "torque" if spec.league.kind == "attitude" else "force"
    out: dict[str, list[Cell]] = {}
    for m in chosen:
        network, delayed = _network_kind(spec, m)
        cells = []
        for case in battery.cases:
            if not case.applies_to(network=network, delayed=delayed):
                continue
            net_fields = case.network_fields(delayed=delayed) if network else None
            for level in spec.levels:
                act = case.actuator_fields(saturation=level.saturation, quantity=quantity)
                raw = method_scenario(spec, m, level, act, net_fields)
                try:
                    load_scenario(raw)
                except Exception as exc:  # noqa: BLE001 - any invalid cell: name it, exit code 2
                    raise LeagueError(f"method {m.name} cannot run cell {case.name}/{level.name} of league "
                                      f"{spec.league.name}: {exc}") from None
                cells.append(Cell(m.name, case.name, case.kind, level.name, raw))
        out[m.name] = cells
    return out


def _network_kind(spec: LeagueSpec, m: MethodEntry) -> tuple[bool, bool]:
    """(has a network, the network has delays) of a method's own file."""
    import tomllib

    assert spec.source is not None
    net = tomllib.loads((spec.source.parent / m.scenario).read_text()).get("network")
    if net is None:
        return False, False
    return True, net.get("delays") is not None


def _campaign(spec: LeagueSpec, method: str, cell_files: list[Path], seeds: int, traced: list[int],
              networked: bool) -> dict:
    ie = spec.league.initial_error
    sample: dict[str, Any] = {}
    if ie.seed_field is not None:
        if not ie.seed_field.startswith("plant."):
            raise LeagueError(f"league.initial_error.seed_field = {ie.seed_field!r}: must name a plant field")
        sample[ie.seed_field] = {"dist": "integer", "low": 0, "high": 2**31 - 1}
    else:
        truth_field = str(ie.field)
        if not truth_field.startswith("plant."):
            raise LeagueError(f"league.initial_error.field = {truth_field!r}: must name a plant field (plant.*)")
        nominal = spec.truth.get(truth_field.removeprefix("plant."))
        if not isinstance(nominal, list) or not all(isinstance(r, list) for r in nominal):
            raise LeagueError(f"league.initial_error.field = {truth_field!r}: [truth] has no list of "
                              "per-spacecraft vectors there")
        if ie.std and ie.std > 0:
            for i, row in enumerate(nominal):
                for k, v in enumerate(row):
                    sample[f"{truth_field}.{i}.{k}"] = {"dist": "normal", "mean": float(v), "std": ie.std}
    overrides: dict[str, Any] = {}
    on = spec.league.onset
    # the actuator fault's onset, and the communication fault's where the method has a network
    for path in (on.field, "network.onset") if networked else (on.field,):
        if on.high > on.low:
            sample[path] = {"dist": "uniform", "low": on.low, "high": on.high}
        else:
            overrides[path] = on.low
    return {
        "campaign": {"name": f"league-{spec.league.name}-{method}", "base": [str(p) for p in cell_files],
                     # a chunk never spans two cells: no larger than the seeds (no padded runs)
                     "runs": seeds, "seed": spec.league.seed, "chunk_size": min(spec.league.chunk_size, seeds),
                     "paired": True, "description": f"league {spec.league.name}: {method}"},
        "overrides": overrides,
        "sample": sample,
        "traces": {"runs": traced, "every": 1},
    }


def _provenance() -> dict[str, Any]:
    from formation_ftc.provenance import provenance

    try:
        return dict(provenance())
    except Exception:  # noqa: BLE001 - provenance is best effort, never a reason to fail a league
        return {}


def _run_method_campaign(campaign: dict, out_dir: str) -> tuple[int, int, float]:
    """One method's campaign in this process (a worker of :func:`run_league`): (runs, failed, seconds)."""
    from formation_ftc.campaign.executors import LocalExecutor
    from formation_ftc.campaign.runner import run_campaign

    t0 = time.perf_counter()
    outcome = run_campaign(campaign, out_dir, executor=LocalExecutor(workers=1))
    return outcome.n_runs, outcome.n_failed, time.perf_counter() - t0


def run_league(league: str | Path | LeagueSpec, out_dir: str | Path, *, seeds: int | None = None,
               quick: bool = False, methods: list[str] | None = None, executor_factory: Callable | None = None,
               progress: bool = False, log: Callable[[str], None] | None = None,
               parallel_methods: int = 1) -> LeagueOutcome:
    """Run (or resume) ``league`` into ``out_dir``: ``DIR/league.json`` (definition, battery, seeds,
    provenance) and one campaign directory per method (``DIR/<method>/campaign``).

    ``parallel_methods`` > 1: that many methods run side by side, one process each (each method's chunks
    in that process); otherwise the methods run one after the other, each campaign with the executor from
    ``executor_factory`` (local processes by default, or Dask)."""
    import tomli_w

    from formation_ftc.campaign.runner import run_campaign

    t0 = time.perf_counter()
    spec = league if isinstance(league, LeagueSpec) else load_league(league)
    n_seeds = int(seeds if seeds is not None else (spec.league.quick_seeds if quick else spec.league.seeds))
    if n_seeds < 1:
        raise LeagueError(f"--seeds = {n_seeds}: at least 1 seed per cell")
    cells = plan_cells(spec, methods)  # everything validated before anything is written
    for name, mcells in cells.items():
        networked = _network_kind(spec, spec.method(name))[0]
        sampled = _campaign(spec, name, [], 1, [], networked)
        for path in [*sampled["sample"], *sampled["overrides"]]:
            for c in mcells:
                if not _has_path(c.raw, path):
                    raise LeagueError(f"league {spec.league.name}: the league samples {path!r}, but method {name}'s "
                                      f"cell {c.key} has no such field (give it a value in [truth], [actuator] or "
                                      "the method's network)")
    battery = _battery(spec)
    out = Path(out_dir)
    digest = league_hash(spec)
    meta_path = out / LEAGUE_FILE
    if meta_path.exists():
        old = json.loads(meta_path.read_text())
        if old.get("hash") != digest or old.get("seeds") != n_seeds:
            raise LeagueError(f"{out}: holds league {old.get('name')!r} (definition {str(old.get('hash'))[:12]}, "
                              f"{old.get('seeds')} seeds); this is {spec.league.name!r} ({digest[:12]}, {n_seeds} "
                              "seeds). Use another --out directory")
    out.mkdir(parents=True, exist_ok=True)
    assert spec.source is not None
    meta = {
        "name": spec.league.name, "version": spec.league.version, "kind": spec.league.kind, "hash": digest,
        "seeds": n_seeds,
        "quick": quick, "definition_file": spec.source.name, "definition": spec.source.read_text(),
        "method_files": {m.name: (spec.source.parent / m.scenario).read_text() for m in spec.methods},
        "battery": {"name": battery.name, "version": battery.version, "sha256": battery.sha256,
                    "cases": [{"name": c.name, "kind": c.kind} for c in battery.cases]},
        "methods": [m.model_dump() for m in spec.methods if m.name in cells],
        "levels": [lv.model_dump() for lv in spec.levels],
        "provenance": _provenance(),
    }
    meta_path.write_text(json.dumps(meta, indent=1, default=str))
    per_method: dict[str, float] = {}
    n_runs = n_failed = 0
    jobs = []
    for name, mcells in cells.items():
        cdir = out / name / "cells"
        cdir.mkdir(parents=True, exist_ok=True)
        files = []
        for c in mcells:
            p = cdir / f"{c.key}.toml"
            text = tomli_w.dumps(c.raw)  # tomli_w writes tuples as arrays and inf as ``inf``
            if not p.exists() or p.read_text() != text:
                p.write_text(text)
            files.append(p)
        traced = _traced_runs(mcells, n_seeds, spec.league.trace_seed, spec.league.trace_cases)
        jobs.append((name, _campaign(spec, name, files, n_seeds, traced, _network_kind(spec, spec.method(name))[0])))

    def done(name: str, runs: int, failed: int, seconds: float) -> None:
        nonlocal n_runs, n_failed
        per_method[name] = seconds
        n_runs += runs
        n_failed += failed
        if log is not None:
            log(f"{name}: {runs} runs, {failed} failed, {seconds:.1f} s")

    if parallel_methods > 1 and len(jobs) > 1:
        # one process per method (each compiles its program once and runs its chunks in-process):
        # the methods' campaigns are independent directories, so they run side by side
        import concurrent.futures
        import multiprocessing

        ctx = multiprocessing.get_context("spawn")
        with concurrent.futures.ProcessPoolExecutor(max_workers=min(parallel_methods, len(jobs)),
                                                    mp_context=ctx) as pool:
            futures = {pool.submit(_run_method_campaign, campaign, str(out / name / "campaign")): name
                       for name, campaign in jobs}
            for fut in concurrent.futures.as_completed(futures):
                runs, failed, seconds = fut.result()
                done(futures[fut], runs, failed, seconds)
    else:
        for name, campaign in jobs:
            t_m = time.perf_counter()
            executor = executor_factory() if executor_factory is not None else None
            outcome = run_campaign(campaign, out / name / "campaign", executor=executor, progress=progress)
            done(name, outcome.n_runs, outcome.n_failed, time.perf_counter() - t_m)
    return LeagueOutcome(out, n_runs, n_failed, time.perf_counter() - t0, per_method)


def _has_path(raw: dict, path: str) -> bool:
    node: Any = raw
    for part in path.split("."):
        if isinstance(node, dict) and part in node:
            node = node[part]
        elif isinstance(node, list) and part.isdigit() and int(part) < len(node):
            node = node[int(part)]
        else:
            return False
    return True


def _traced_runs(cells: list[Cell], seeds: int, trace_seed: int, cases: list[str]) -> list[int]:
    """Run ids whose time histories are kept: the trace seed of the trace cases at the first level
    (each kept history is one more run, re-run alone with its records)."""
    j = min(trace_seed, seeds - 1)
    first_level = cells[0].level if cells else ""
    return [g * seeds + j for g, c in enumerate(cells) if c.level == first_level and c.case in cases]


def load_league_results(out_dir: str | Path) -> tuple[dict[str, Any], pd.DataFrame]:
    """``(league.json, one row per run)`` with columns method, case, fault_kind, level, replicate, seed,
    status, diagnostic and ``metric:*``."""
    from formation_ftc.campaign.storage import CampaignStore

    out = Path(out_dir)
    meta_path = out / LEAGUE_FILE
    if not meta_path.is_file():
        raise LeagueError(f"{out}: no {LEAGUE_FILE}; run `formation-ftc league run NAME --out {out}` first")
    meta = json.loads(meta_path.read_text())
    kinds = {c["name"]: c["kind"] for c in meta["battery"]["cases"]}
    frames = []
    for m in meta["methods"]:
        cdir = out / m["name"] / "campaign"
        if not cdir.is_dir():
            continue
        df = CampaignStore.read(cdir).load_results()
        if not len(df):
            continue
        keys = df["scenario"].map(lambda s: Path(str(s)).stem)
        df = df.assign(method=m["name"], case=keys.str.split("--").str[0], level=keys.str.split("--").str[1])
        df["fault_kind"] = df["case"].map(kinds)
        frames.append(df)
    if not frames:
        raise LeagueError(f"{out}: no finished runs yet")
    return meta, pd.concat(frames, ignore_index=True)
