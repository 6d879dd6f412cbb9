"""Execute a campaign: chunks of runs as ``jax.vmap`` batches, results stored chunk by chunk.

A chunk (see :mod:`formation_ftc.campaign.sampling`) is computed by :func:`run_chunk`, a pure
function of ``(plan, chunk)`` that any executor may call in any process. Methods whose parameters are
a closed loop take the fast path (``_bound_chunk``): the chunk's inputs are derived as columns, the
sampled values written into the parameter arrays of one template build
(:mod:`formation_ftc.campaign.binding`), the batch run without time histories and the result table
assembled from the metric arrays; only failed and traced runs are handled one by one. Otherwise:

1. build each run's scenario (base + overrides + grid/sampled values + run seed) and its loop
   (:func:`formation_ftc.api.build_loop`);
2. group the runs by ``ClosedLoop.static_key`` (one group per chunk unless a random ``choice`` changes
   the structure), stack the leaves that differ between the runs (the others are shared,
   ``in_axes=None``, see :func:`formation_ftc.sim.batch.stack_params`) and call ``jax.jit(jax.vmap(ClosedLoop.run))`` -- one jitted
   function per static key and set of batched leaves, reused by every chunk, the batch padded to
   ``chunk_size`` so the last chunk does not recompile;
3. per run, ``ClosedLoop.metric_values`` on its slice; a run whose state became non-finite
   (``diverged_step >= 0``) is recorded ``status = "failed"`` with the engine's diagnostic
   (variable, spacecraft, time), its metrics NaN, and the campaign goes on.

:func:`run_campaign` validates everything first (campaign file, dotted paths, sampler bounds, every
run's scenario, the metric names, the results directory, the executor's scheduler), then submits the
unfinished chunks and writes each result atomically as it arrives, with a progress bar (runs done;
runs/s and ETA over the whole wall time since the caller's start, compilation included). In-process, the work of consecutive chunks overlaps: chunk k+1 is started
(:func:`start_chunk`: parameter batch built, program dispatched) before chunk k is finished, and chunk
k is written by a background writer thread while chunk k+1 computes; the stored numbers are those of
:func:`run_chunk`.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Collection, Iterator, Mapping, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import jax
import numpy as np
import pandas as pd

from formation_ftc.campaign.sampling import CampaignPlan, Chunk, ChunkList, RunColumns, all_numbers
from formation_ftc.campaign.spec import CampaignError, CampaignSpec, load_campaign
from formation_ftc.campaign.storage import CampaignStore
from formation_ftc.progress import _Bars, _clock, _since
from formation_ftc.sim.batch import batched_run, stack_params
from formation_ftc.sim.programs import jitted_run

__all__ = [
    "ChunkResult",
    "CampaignOutcome",
    "run_chunk",
    "start_chunk",
    "run_campaign",
    "metric_names",
    "make_plan",
]


@dataclass
class ChunkResult:
    chunk_id: int
    table: pd.DataFrame
    traces: dict[int, Any] = field(default_factory=dict)
    wall_s: float = 0.0

    @property
    def n_runs(self) -> int:
        return len(self.table)


@dataclass
class CampaignOutcome:
    """What :func:`run_campaign` did: counts over the whole results directory (``n_runs`` of the
    ``n_planned``, ``n_failed``, ``n_diverged``, ``results``), what this call computed (``n_computed`` runs in ``chunks_computed`` chunks; the others
    were kept from an earlier run) and the wall time the caller waited (``wall_s`` [s], from
    ``started``: everything from planning to loading the results). ``rate`` [runs/s] is
    ``n_computed / wall_s``."""

    out_dir: Path
    n_runs: int
    n_failed: int
    chunks_total: int
    chunks_computed: int
    chunks_resumed: int
    wall_s: float
    results: pd.DataFrame
    executor: str = ""
    name: str = ""
    n_planned: int = 0
    n_computed: int = 0
    n_diverged: int = 0
    units: dict[str, str] = field(default_factory=dict)  # metric:<name> column -> UDUNITS unit

    @property
    def n_kept(self) -> int:
        """Runs kept from an earlier run of the campaign (not computed by this call)."""
        return self.n_runs - self.n_computed

    @property
    def rate(self) -> float | None:
        """Runs computed per second of the whole wall time [1/s]; None when none was computed."""
        return self.n_computed / self.wall_s if self.n_computed and self.wall_s > 0 else None

    def _rate_text(self) -> str:
        return "" if self.rate is None else f", {self.rate:.3g} runs/s"

    def __str__(self) -> str:
        return (
            f"{self.n_runs} runs ({self.n_runs - self.n_failed} ok, {self.n_failed} failed) in "
            f"{self.out_dir}; {self.chunks_computed} chunk(s) computed, {self.chunks_resumed} kept from "
            f"an earlier run, {self.wall_s:.1f} s{self._rate_text()}"
        )

    def __repr__(self) -> str:
        return (
            f"<CampaignOutcome {self.name!r}: {self.n_runs} runs ({self.n_failed} failed), "
            f"{self.n_computed} computed in {self.wall_s:.1f} s{self._rate_text()}, "
            f"dir {str(self.out_dir)!r}>"
        )

    def _repr_html_(self) -> str:
        """Jupyter: counts, wall time and rate, then each metric's median and 5-95 % range with its
        unit (formation_ftc.display)."""
        from formation_ftc.display import card_html, number, quantity

        fields = [
            ("directory", str(self.out_dir)),
            (
                "runs",
                f"{self.n_runs:,} ({self.n_runs - self.n_failed:,} ok, {self.n_failed:,} failed)",
            ),
            ("this call", f"{self.n_computed:,} runs computed, {self.n_kept:,} kept"),
            ("chunks", f"{self.chunks_computed} computed, {self.chunks_resumed} kept"),
            ("wall time", f"{number(self.wall_s)} s" + self._rate_text()),
            ("executor", self.executor),
        ]
        rows = []
        for col in (c for c in self.results.columns if str(c).startswith("metric:")):
            v = pd.to_numeric(self.results[col], errors="coerce").to_numpy(float)
            ok = v[np.isfinite(v)]
            u = self.units.get(col, "")
            p5, p50, p95 = np.percentile(ok, [5, 50, 95]) if ok.size else (np.nan,) * 3
            spread = f"{number(p5)} .. {number(p95)}"
            rows.append([col.removeprefix("metric:"), f"{ok.size:,}", quantity(p50, u), spread, u])
        return card_html(
            f"campaign {self.name}",
            "",
            fields,
            ("metric", "finite", "median", "5 .. 95 %", "units") if rows else (),
            rows,
        )


def _columns(plan: CampaignPlan, chunk: Chunk, cols: RunColumns) -> dict[str, Any]:
    """A chunk's result columns before its outcomes: bookkeeping, then ``status`` and ``diagnostic``
    (placeholders, set by the caller), then one ``input:<path>`` column per sampled field (a number,
    else the text or its JSON)."""
    n = len(cols)
    data: dict[str, Any] = {
        "run_id": cols.run_id.astype(np.int64),
        "chunk_id": np.full(n, chunk.chunk_id, dtype=np.int64),
        "grid_index": cols.grid_index.astype(np.int64),
        "replicate": cols.replicate.astype(np.int64),
        "seed": cols.seed.astype(np.int64),
        "scenario": [plan.base_names[b] for b in cols.base.tolist()],
        "status": None,
        "diagnostic": None,
    }
    numeric = plan.input_columns()
    for path, vals in cols.values.items():
        if numeric[f"input:{path}"]:
            data[f"input:{path}"] = np.asarray(vals, dtype=np.float64)
        else:
            data[f"input:{path}"] = [v if isinstance(v, str) else json.dumps(v) for v in vals]
    return data


def _diagnostic(loop, out: Mapping[str, Any]) -> str:
    """What the engine says about the divergence of a failed run (variable, spacecraft, time)."""
    from formation_ftc.api import _divergence_info

    return str(_divergence_info(loop, out, int(out["diverged_step"])))


def _require_metrics(keep: Sequence[str], returned: Collection[str], method: str) -> None:
    """Refuse a kept metric that the method does not return (``returned``: its metric names)."""
    if missing := [m for m in keep if m not in returned]:
        raise CampaignError(
            f"campaign.metrics: {missing} not returned by method "
            f"{method!r} (it returns {sorted(returned)})"
        )


def _trace(plan: CampaignPlan, loop, scenario, inputs, out: Mapping[str, Any], status: str):
    from formation_ftc.sim.engine import trim_records

    tr = plan.spec.traces
    records, n_kept = trim_records(out["records"], int(out["diverged_step"]), loop.record_every)
    ds = loop.dataset(dict(out, records=records), n_kept)
    if tr.variables:
        if missing := [v for v in tr.variables if v not in ds.data_vars]:
            raise CampaignError(
                f"traces.variables: {missing} not in the dataset (has {list(ds.data_vars)})"
            )
        ds = ds[tr.variables]
    ds = ds.isel(time=slice(None, None, tr.every))
    ds.attrs.update(
        campaign=plan.name,
        run_id=inputs.run_id,
        seed=inputs.seed,
        status=status,
        scenario_name=scenario.scenario.name,
        inputs_json=json.dumps(inputs.values, default=str),
    )
    return ds


#: per-process cache: (plan hash, group key) -> (template loop, bindings) or None (not bindable)
_BINDINGS: dict[Any, Any] = {}
#: cache keys of _BINDINGS whose bound parameters matched a per-run build in this process
_VERIFIED: set[Any] = set()


def clear_bindings() -> None:
    """Forget this process's bound-parameter templates (each holds a built scenario and its program)."""
    _BINDINGS.clear()
    _VERIFIED.clear()


def _bound_chunk(
    plan: CampaignPlan, chunk: Chunk, cols: RunColumns, t_start: float
) -> Callable[[], ChunkResult] | None:
    """The fast path: one build per structural group, sampled values written into the leaves their
    paths name (:mod:`formation_ftc.campaign.binding`), metrics read as arrays from the batched run and
    the result table assembled from columns (no per-run Python objects except for failed and traced
    runs). None when a field cannot be bound.

    Returns the chunk's *finisher*: the batch has been dispatched (JAX computes asynchronously) and
    the finisher waits for it, reads the metrics, assembles the table and re-runs the failed and
    traced runs, so a caller may start the next chunk first."""
    from formation_ftc import api
    from formation_ftc.campaign import binding
    from formation_ftc.sim.metrics import metric_names as loop_metric_names

    n = len(cols)
    bindable = [
        s.path
        for s in plan.random_samplers
        if s.numeric and s.kind != "choice" and all_numbers(cols.values[s.path])
    ]
    base_names = [plan.base_names[b] for b in cols.base.tolist()]
    structural = [p for p in cols.values if p not in bindable]  # grid values (constant) and choices

    def group_key(k: int) -> str:
        structure = json.dumps(
            {p: cols.values[p][k] for p in structural}, sort_keys=True, default=str
        )
        return f"{base_names[k]}|{structure}"

    gkey = group_key(0)
    varying = [p for p in structural if any(v != cols.values[p][0] for v in cols.values[p])]
    if len(set(base_names)) > 1 or (varying and any(group_key(k) != gkey for k in range(1, n))):
        return None  # structure differs inside the chunk (a choice): the general path groups it
    first = cols.row(0, plan.base_names)
    cache_key = (plan.hash, gkey)
    if cache_key not in _BINDINGS:
        template = api.build_loop(plan.scenario(first))
        values0 = {**{p: first.values[p] for p in bindable}, binding.SEED_PATH: first.seed}
        bindings = binding.bind_fields(template, values0)
        # the batch needs no time histories (metrics are computed inside the run): one record at the
        # start and one at the end; trace runs and failed runs are re-run alone with records. An STL
        # requirement is evaluated on the records inside the run: it keeps the scenario's interval
        stl = any(m.formula is not None for m in template.metrics)
        lean = template if stl else replace(template, record_every=template.n_steps)
        _BINDINGS[cache_key] = None if bindings is None else (lean, bindings)
    entry = _BINDINGS[cache_key]
    if entry is None:
        return None
    template, bindings = entry
    values = {p: np.asarray(cols.values[p], dtype=np.float64) for p in bindable}
    values[binding.SEED_PATH] = cols.seed.astype(np.float64)
    batch, axes = binding.apply_bindings(template, bindings, values, plan.chunk_size)
    engine = batched_run(template, axes, plan.chunk_size)
    # a group whose binding was verified before in this process starts computing now (JAX dispatches
    # asynchronously) and the Python work below overlaps it; a first chunk is verified first
    pending = engine(batch) if cache_key in _VERIFIED else None
    check = api.build_loop(plan.scenario(cols.row(n - 1, plan.base_names)))
    check_params = replace(check, record_every=template.record_every)
    if not binding.params_close(check_params, binding.take_run(batch, axes, n - 1)):
        _BINDINGS[cache_key] = None  # a field moves another leaf too (or fields interact): per run
        _VERIFIED.discard(cache_key)
        return None  # (a speculative batch in flight is dropped)
    _VERIFIED.add(cache_key)
    if pending is None:
        pending = engine(batch)
    data = _columns(plan, chunk, cols)

    def finish() -> ChunkResult:
        out = jax.device_get(pending)
        names = loop_metric_names(template.metrics, template.count)
        # one column per name: a per-spacecraft metric's (runs, spacecraft) array gives one per spacecraft
        columns = [
            c for a in out["metrics"] for c in np.asarray(a, np.float64)[:n].reshape(n, -1).T
        ]
        metric_cols = dict(zip(names, columns, strict=True))
        keep = plan.spec.campaign.metrics
        _require_metrics(keep, names, plan.scenario(cols.row(0, plan.base_names)).scenario.method)
        failed = np.asarray(out["diverged_step"])[:n] >= 0
        data.update(status=np.where(failed, "failed", "ok"), diagnostic=[""] * n)
        for name in keep or names:
            data[f"metric:{name}"] = np.where(failed, np.nan, metric_cols[name]).astype("float64")
        table = pd.DataFrame(data)
        traces = {}
        trace_runs = set(plan.spec.traces.runs)
        for j in np.flatnonzero(failed | np.isin(cols.run_id, list(trace_runs))).tolist():
            # re-run alone with the scenario's records (and the replay that names a divergence)
            inp = cols.row(j, plan.base_names)
            scn = plan.scenario(inp)
            # the scenario's recording interval (structural: the batch ran with one record at each end)
            loop_j = replace(
                binding.take_run(batch, axes, j), record_every=int(scn.simulation.record_every)
            )
            run_out = jax.device_get(jitted_run(loop_j)(loop_j))
            if failed[j]:
                table.at[j, "diagnostic"] = _diagnostic(loop_j, run_out)
            if inp.run_id in trace_runs:
                traces[inp.run_id] = _trace(
                    plan, loop_j, scn, inp, run_out, str(table.at[j, "status"])
                )
        table.attrs["metric_units"] = _metric_units(template.metrics, template.count)
        return ChunkResult(chunk.chunk_id, table, traces, time.perf_counter() - t_start)

    return finish


def run_chunk(plan: CampaignPlan, chunk: Chunk) -> ChunkResult:
    """Compute one chunk (pure function of its arguments; safe in worker processes and on Dask)."""
    return start_chunk(plan, chunk)()


def start_chunk(plan: CampaignPlan, chunk: Chunk) -> Callable[[], ChunkResult]:
    """Start one chunk and return the call that finishes it (same result as :func:`run_chunk`).

    On the bound-parameter path the batch is dispatched before this returns and JAX computes it
    asynchronously, so an in-process executor starts chunk k+1 (building its parameter batch, queueing
    its program) before it finishes chunk k (waiting, metrics table, re-runs of failed runs) and the
    Python work of one chunk overlaps the computation of the other."""
    t_start = time.perf_counter()
    cols = plan.run_columns(chunk.run_ids)
    fast = _bound_chunk(plan, chunk, cols, t_start)
    if fast is not None:
        return fast
    result = _general_chunk(plan, chunk, cols, t_start)
    return lambda: result


def _general_chunk(
    plan: CampaignPlan, chunk: Chunk, cols: RunColumns, t_start: float
) -> ChunkResult:
    """Per-run builds grouped by structure (a chunk whose structure varies, or a field that cannot be
    bound)."""
    from formation_ftc import api

    inputs = cols.rows(plan.base_names)
    scenarios = [plan.scenario(i) for i in inputs]
    loops = [api.build_loop(s) for s in scenarios]
    groups: dict[Any, list[int]] = {}
    for k, c in enumerate(loops):
        groups.setdefault(c.static_key, []).append(k)
    outs: list[Any] = [None] * len(loops)
    for idxs in groups.values():
        stacked, axes = stack_params([loops[k] for k in idxs], plan.chunk_size)
        batch = jax.device_get(batched_run(loops[idxs[0]], axes, plan.chunk_size)(stacked))
        for pos, k in enumerate(idxs):
            outs[k] = jax.tree_util.tree_map(lambda a, pos=pos: np.asarray(a[pos]), batch)
    keep = plan.spec.campaign.metrics
    data = _columns(plan, chunk, cols)
    status, diagnostic, metrics, traces = [], [], [], {}
    for inp, scn, comp, out in zip(inputs, scenarios, loops, outs, strict=True):
        div = int(out["diverged_step"])
        if div < 0:
            with np.errstate(all="ignore"):
                metrics.append({k: float(v) for k, v in comp.metric_values(out).items()})
            _require_metrics(keep, metrics[-1], scn.scenario.method)
        else:
            metrics.append({})  # NaN metrics
        status.append("ok" if div < 0 else "failed")
        diagnostic.append("" if div < 0 else _diagnostic(comp, out))
        if inp.run_id in plan.spec.traces.runs:
            traces[inp.run_id] = _trace(plan, comp, scn, inp, out, status[-1])
    data.update(status=status, diagnostic=diagnostic)
    for name in keep or dict.fromkeys(k for m in metrics for k in m):
        data[f"metric:{name}"] = np.array([m.get(name, np.nan) for m in metrics], dtype=np.float64)
    table = pd.DataFrame(data)
    table.attrs["metric_units"] = _metric_units(loops[0].metrics, loops[0].count)
    return ChunkResult(chunk.chunk_id, table, traces, time.perf_counter() - t_start)


def _metric_units(metrics, count: int) -> dict[str, str]:
    """``metric:<name>`` column -> UDUNITS unit of the declared metric (per-spacecraft names expanded)."""
    from formation_ftc.api import _metric_units as units

    return {f"metric:{n}": u for n, u in units(metrics, count).items()}


def metric_names(plan: CampaignPlan) -> dict[str, list[str]]:
    """Metric names each base scenario's loop declares (found without running anything)."""
    from formation_ftc import api
    from formation_ftc.sim.metrics import metric_names as loop_metric_names

    out: dict[str, list[str]] = {}
    for b, name in enumerate(plan.base_names):
        g = b * (plan.n_grid // len(plan.base_names))  # base b, first value of every grid field
        loop = api.build_loop(plan.scenario(plan.run_inputs(g * plan.runs)))
        out[name] = loop_metric_names(loop.metrics, loop.count)
    return out


def make_plan(
    campaign: str | Path | Mapping[str, Any] | CampaignSpec | CampaignPlan,
    *,
    runs: int | None = None,
    chunk_size: int | None = None,
) -> CampaignPlan:
    """Campaign name/path/dict/spec -> validated :class:`CampaignPlan` (nothing runs)."""
    if isinstance(campaign, CampaignPlan):
        if runs is not None or chunk_size is not None:
            raise CampaignError(
                "runs/chunk_size overrides need a campaign file or spec, not a plan"
            )
        return campaign
    if isinstance(campaign, CampaignSpec):
        campaign = campaign.model_dump(mode="json")
    spec, base_dir = load_campaign(campaign, runs=runs, chunk_size=chunk_size)
    return CampaignPlan(spec, base_dir, drop_missing_traces=runs is not None)


def _progress_bar(enabled: bool, total: int, done: int, name: str, started: float) -> _Bars:
    """The progress bar of :func:`run_campaign` (on stderr; a no-op when not ``enabled``): runs stored,
    then runs/s, elapsed time and ETA over the whole wall time since ``started`` (a
    ``time.perf_counter`` value; planning and compilation included), counting only the runs computed
    since then (not those kept from an earlier run). Its one line is advanced by the runs stored."""

    def rate(task) -> float:
        elapsed = time.perf_counter() - started
        return (task.completed - done) / elapsed if elapsed > 0 else 0.0

    def rate_text(task) -> str:
        r = rate(task)
        return f"{r:.3g} runs/s" if r > 0 else "-- runs/s"

    def time_left(task) -> str:
        r = rate(task)
        left = (task.total - task.completed) / r if r > 0 else None
        return _clock(0.0 if task.finished else left)

    tasks = {name: {"total": total, "completed": done}}
    return _Bars(tasks, "runs", rate_text, _since(started), "ETA", time_left, enabled=enabled)


def run_campaign(
    campaign: str | Path | Mapping[str, Any] | CampaignSpec | CampaignPlan,
    out_dir: str | Path,
    *,
    runs: int | None = None,
    chunk_size: int | None = None,
    executor=None,
    progress: bool = False,
    started: float | None = None,
) -> CampaignOutcome:
    """Run (or resume) a campaign into ``out_dir``; returns counts and the results table.

    Everything that can be checked is checked before the first run: campaign file, dotted paths,
    sampler bounds, every run's scenario, metric names, the results directory (foreign or corrupt:
    refused) and the executor (an unreachable scheduler is an error).

    ``started`` (a ``time.perf_counter()`` value; default: the call) is when the caller's wait began:
    the outcome's ``wall_s`` and the progress bar's runs/s and ETA count from it (the command line
    passes the start of the command, so that they include its planning and budget checks).
    """
    from formation_ftc.campaign.executors import LocalExecutor

    t0 = time.perf_counter() if started is None else started
    plan = make_plan(campaign, runs=runs, chunk_size=chunk_size)
    plan.validate_all()
    if plan.spec.campaign.metrics:
        for base, names in metric_names(plan).items():
            if missing := [m for m in plan.spec.campaign.metrics if names and m not in names]:
                raise CampaignError(
                    f"campaign.metrics: {missing} not returned for base scenario {base!r} "
                    f"(available: {', '.join(names)})"
                )
    store = CampaignStore.prepare(out_dir, plan)
    executor = executor if executor is not None else LocalExecutor()
    done_before = store.finished()
    todo = plan.chunks(done=done_before)
    if hasattr(executor, "prepare"):  # the automatic local pool sizes itself to the work left
        executor.prepare(_run_steps(plan, todo), len(todo))
    with executor:
        store.initialize()  # takes the directory's lock (refused while another run writes there)
        n_done = sum(len(plan.chunk(c)) for c in done_before)
        # chunk k is written (Parquet, checksum, fsync) by one writer thread while chunk k+1 computes;
        # at most one write is in flight and a write error stops the campaign at the next chunk. Leaving
        # the writer (on an error too) waits for a write under way: a finished chunk is never lost
        writing: Future | None = None
        try:
            with (
                _progress_bar(progress, plan.n_runs, n_done, plan.name, t0) as bar,
                ThreadPoolExecutor(max_workers=1, thread_name_prefix="campaign-writer") as writer,
            ):
                for res in _map_in_windows(executor, plan, todo):
                    if writing is not None:
                        bar.update_line(plan.name, advance=writing.result())
                    writing = writer.submit(_store_chunk, store, res)
                if writing is not None:
                    bar.update_line(plan.name, advance=writing.result())
        finally:
            store.close()
    results = store.load_results()
    failed = results["status"] != "ok"
    diagnostic = results.get("diagnostic", pd.Series("", index=results.index)).astype(str)
    return CampaignOutcome(
        Path(out_dir),
        len(results),
        int(failed.sum()),
        plan.n_chunks,
        len(todo),
        len(done_before),
        time.perf_counter() - t0,
        results,
        executor.describe(),
        name=plan.name,
        n_planned=plan.n_runs,
        n_computed=sum(len(c) for c in todo),
        n_diverged=int((failed & diagnostic.str.startswith("simulation diverged")).sum()),
        units={c: u for c, u in store.units().items() if c.startswith("metric:")},
    )


#: chunks handed to the executor at once: what it holds for pending chunks (futures, queued calls) stays
#: bounded in a campaign of millions of chunks, and the pool idles only while a window's last chunks finish
MAP_WINDOW = 4096


def _map_in_windows(executor, plan: CampaignPlan, chunks: ChunkList) -> Iterator[ChunkResult]:
    """``executor.map(run_chunk, plan, chunks)``, :data:`MAP_WINDOW` chunks at a time."""
    for a in range(0, len(chunks), MAP_WINDOW):
        yield from executor.map(run_chunk, plan, chunks[a : a + MAP_WINDOW], start=start_chunk)


def _store_chunk(store: CampaignStore, res: ChunkResult) -> int:
    store.write_chunk(res.chunk_id, res.table, res.traces)
    return res.n_runs


def _run_steps(plan: CampaignPlan, chunks: Sequence[Chunk]) -> int:
    """Integration steps over all runs of ``chunks``: each chunk's first run gives its step count, found
    once per grid point unless a ``simulation.*`` field is sampled."""
    per_chunk = any(s.path.startswith("simulation.") for s in plan.random_samplers)
    per_point: dict[int, int] = {}
    total = 0
    for c in chunks:
        n = per_point.get(c.grid_index)
        if n is None:
            n = int(getattr(plan.scenario(plan.run_inputs(c.start)).simulation, "n_steps", 0) or 0)
            if not per_chunk:
                per_point[c.grid_index] = n
        total += len(c) * n
    return total
