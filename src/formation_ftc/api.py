"""Python API: load a scenario, simulate it, check its conditions.

>>> import formation_ftc as ftc
>>> scn = ftc.load_scenario("cw-free-drift", overrides={"simulation.horizon": 10.0})
>>> ds = ftc.simulate(scn)                     # xarray.Dataset
>>> int(ds.attrs["seed"]), "git_commit" in ds.attrs   # provenance travels with the data
(0, True)
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from formation_ftc.config import loader
from formation_ftc.config.base import ScenarioBase
from formation_ftc.registry import Condition, get_method

if TYPE_CHECKING:  # JAX is imported by the functions that simulate, not with this module
    from formation_ftc.sim.engine import DivergenceInfo
    from formation_ftc.sim.loop import ClosedLoop

__all__ = [
    "load_scenario",
    "list_scenarios",
    "simulate",
    "simulate_with_metrics",
    "check",
    "build_loop",
    "finish_run",
    "result_metrics",
    "metric_units",
    "save_result",
    "Conditions",
    "Metrics",
]


class Conditions(list[Condition]):
    """What :func:`check` returns: a list of :class:`~formation_ftc.registry.Condition` that shows as a
    table (condition, value, requirement, holds) at a Python prompt and in Jupyter."""

    def _card(self) -> dict[str, Any]:
        from formation_ftc.display import CONDITION_COLUMNS, condition_row

        failed = [c.name for c in self if c.required and c.holds is False]
        note = f"required condition(s) failing: {', '.join(failed)}" if failed else ""
        return dict(
            title=f"Conditions ({len(self)})",
            columns=CONDITION_COLUMNS,
            rows=[condition_row(c) for c in self],
            note=note or ("no required condition fails" if self else "no conditions declared"),
        )

    def __repr__(self) -> str:
        from formation_ftc.display import card_text

        return card_text(**self._card())

    def _repr_html_(self) -> str:
        from formation_ftc.display import card_html

        return card_html(**self._card())


class Metrics(dict[str, float]):
    """What :func:`simulate_with_metrics` returns next to the dataset: ``{metric: float}`` (a plain
    dict to any code) with ``units`` (``{metric: UDUNITS string}``); shows as a table of value and unit
    in Jupyter."""

    def __init__(
        self, values: Mapping[str, float] | None = None, units: Mapping[str, str] | None = None
    ):
        super().__init__(values or {})
        self.units: dict[str, str] = dict(units or {})

    def _repr_html_(self) -> str:
        from formation_ftc.display import card_html, number

        rows = [[k, number(v), self.units.get(k, "")] for k, v in self.items()]
        return card_html(f"Metrics ({len(self)})", "", (), ("metric", "value", "units"), rows)


def load_scenario(
    name_or_path: str | Path | Mapping[str, Any],
    overrides: Mapping[str, Any] | Iterable[str] | None = None,
    *,
    build: bool = True,
) -> ScenarioBase:
    """Built-in name, TOML path or raw dict -> validated scenario (overrides applied first).

    Parameters
    ----------
    name_or_path : str, Path, Mapping or ScenarioBase
        A built-in scenario name (``formation-ftc list``), the path of a TOML file, a raw dictionary of
        its tables, or an already loaded scenario (validated again, with the overrides).
    overrides : Mapping or iterable of str, optional
        Field values applied before validation: ``{"simulation.horizon": 300.0}`` or
        ``["controller.kp=3"]`` (dotted paths, list items by index: ``plant.mass.0``).
    build : bool, default True
        Also assemble the loop to check that the components fit together (as ``check`` and ``run``
        do). False checks every field of every section only (what ``formation-ftc show`` does).

    Returns
    -------
    ScenarioBase
        The validated scenario (the method's pydantic model; SI units as its fields state).

    Raises
    ------
    formation_ftc.errors.ScenarioError
        A field out of range, an unknown field or an impossible composition (the message names it).

    Examples
    --------
    >>> from formation_ftc.api import load_scenario
    >>> scn = load_scenario("cw-pd-fault", overrides={"controller.kp": 3.0})
    >>> scn.section("controller").kp, scn.simulation.dt
    (3.0, 0.1)
    """
    if isinstance(name_or_path, ScenarioBase):
        raw, source = name_or_path.model_dump(mode="json", exclude_none=True), "<scenario object>"
    elif isinstance(name_or_path, Mapping):
        raw, source = dict(name_or_path), "<dict>"
    else:
        raw, source = loader.read_raw(name_or_path)
    raw = loader.apply_overrides(raw, overrides)
    return loader.validate(raw, source, build=build)


def list_scenarios() -> dict[str, str]:
    """Built-in scenario name -> one-line description.

    Returns
    -------
    dict of str to str
        Every built-in scenario (what ``formation-ftc list`` prints), sorted by name.

    Examples
    --------
    >>> from formation_ftc.api import list_scenarios
    >>> "li2020-thm1" in list_scenarios()
    True
    """
    import tomllib

    return {
        name: str(tomllib.loads(text).get("scenario", {}).get("description", ""))
        for name, text in loader.builtin_scenarios().items()
    }


def build_loop(scenario: ScenarioBase) -> ClosedLoop:
    """The scenario's closed loop, its components checked against each other (no JAX compilation
    happens yet). It carries the scenario's step, horizon, seed and admissible set
    (:meth:`~formation_ftc.sim.loop.ClosedLoop.from_simulation`); ``loop.run()`` is the pure run.

    Parameters
    ----------
    scenario : ScenarioBase
        A validated scenario (:func:`load_scenario`).

    Returns
    -------
    formation_ftc.sim.loop.ClosedLoop
        Every number a leaf (gains, masses, faults, seed), every structural choice static (components,
        step ``dt`` [s], number of steps, record interval).

    Raises
    ------
    CompositionError
        Components that cannot work together (from :meth:`~formation_ftc.sim.loop.ClosedLoop.validate`).

    Examples
    --------
    >>> from formation_ftc.api import build_loop, load_scenario
    >>> loop = build_loop(load_scenario("cw-pd-fault"))
    >>> loop.dt, loop.n_steps
    (0.1, 6000)
    """
    return get_method(scenario.scenario.method).build(scenario)


def finish_run(
    scenario: ScenarioBase, loop: ClosedLoop, out: dict, raise_on_divergence: bool = True
):
    """numpy RunOutput -> (Dataset with provenance, metrics); raises SimulationDiverged with .partial.

    Parameters
    ----------
    scenario : ScenarioBase
        The scenario that was run (recorded in the dataset's attributes).
    loop : formation_ftc.sim.loop.ClosedLoop
        Its loop (:func:`build_loop`).
    out : dict
        What the compiled run returned (records, metrics, final state, ``diverged_step``).
    raise_on_divergence : bool, optional
        Raise :class:`~formation_ftc.sim.engine.SimulationDiverged` (default) or return the partial
        result of a diverged run, its diagnostic in ``ds.attrs["diverged"]``.

    Returns
    -------
    tuple of (xarray.Dataset, dict of str to float)
        The CF-1.10 dataset with provenance, and the scalar metrics (SI units, see :func:`metric_units`).

    Examples
    --------
    >>> from formation_ftc.api import build_loop, finish_run, load_scenario
    >>> from formation_ftc.sim.programs import jitted_run
    >>> scn = load_scenario("cw-free-drift", {"simulation.horizon": 10.0})
    >>> loop = build_loop(scn)
    >>> ds, metrics = finish_run(scn, loop, jitted_run(loop)(loop))
    >>> ds.sizes["spacecraft"], ds.attrs["diverged"]
    (2, '')
    """
    import jax
    import numpy as np

    from formation_ftc.cf import apply_cf
    from formation_ftc.provenance import provenance
    from formation_ftc.sim.engine import SimulationDiverged, trim_records

    out = jax.tree_util.tree_map(np.asarray, dict(out))
    div = int(out["diverged_step"])
    out["records"], n_kept = trim_records(out["records"], div, loop.record_every)
    ds = loop.dataset(out, n_kept)
    metrics = {k: float(v) for k, v in loop.metric_values(out).items()}
    units = _metric_units(loop.metrics, loop.count)
    ds.attrs.update(
        provenance(),
        scenario_name=scenario.scenario.name,
        method=scenario.scenario.method,
        scenario_toml=loader.dump_toml(scenario),
        seed=int(scenario.simulation.seed),
        metrics_json=json.dumps(metrics),
        metric_units_json=json.dumps({k: units.get(k, "1") for k in metrics}),
        diverged="",
    )
    # CF-1.10 global attributes and per-variable metadata (formation_ftc.cf)
    apply_cf(
        ds,
        scenario_name=scenario.scenario.name,
        method=scenario.scenario.method,
        description=scenario.scenario.description,
        references=_references(scenario),
        created_utc=str(ds.attrs.get("created_utc", "")),
        version=str(ds.attrs.get("version_formation-ftc", "")),
    )
    if div >= 0:
        info = _divergence_info(loop, out, div)
        ds.attrs["diverged"] = str(info)
        ds.attrs["history"] += f"\n{ds.attrs['created_utc']} diverged: {info}"
        if raise_on_divergence:
            raise SimulationDiverged(info, partial=ds)
    return ds, metrics


def _divergence_info(loop: ClosedLoop, out: Mapping[str, Any], div: int) -> DivergenceInfo:
    """Where and what diverged in the run ``out`` of ``loop`` (first non-finite step ``div``):
    replayed from the last finite state. A replay that cannot run gives the step and time alone: a
    diagnostic never loses the run (also used by campaigns)."""
    from formation_ftc.sim.engine import DivergenceInfo, diagnose_divergence

    t = loop.t0 + div * loop.dt
    try:
        return diagnose_divergence(
            loop.replay_step(),
            out["last_finite"],
            div,
            t,
            loop.spacecraft_axis,
            max_steps=loop.record_every,
            dt=loop.dt,
            admissible=loop.admissible,
            violations=loop.violations,
            params=loop,
        )
    except Exception:  # noqa: BLE001 - the run and its partial results matter more
        return DivergenceInfo(div, t, "<state>", None, ())


def _references(scenario: ScenarioBase) -> str:
    """Citation of the paper the scenario reproduces (and its method's description), for ``references``."""
    from formation_ftc.registry import reproductions

    refs = []
    paper = getattr(scenario.scenario, "paper", None)
    reps = reproductions()
    for key in filter(None, (paper, scenario.scenario.method)):
        rep = reps.get(key)
        if rep is not None and rep.citation and rep.citation not in refs:
            refs.append(rep.citation)
    return "\n".join(refs)


def simulate_with_metrics(scenario: ScenarioBase | str | Path, raise_on_divergence: bool = True):
    """Run one scenario: ``(xarray.Dataset, {metric: float})``; a run that diverges raises
    :class:`SimulationDiverged` (``raise_on_divergence=False``: returns what it computed instead).

    The process keeps one compiled program per structure (:func:`formation_ftc.sim.programs.jitted_run`):
    running a scenario again with other numbers -- a gain, a fault time, a seed -- reuses it (no
    tracing, no compilation).

    Parameters
    ----------
    scenario : ScenarioBase, str or Path
        A loaded scenario, a built-in name or a TOML path.
    raise_on_divergence : bool, optional
        See :func:`finish_run`.

    Returns
    -------
    tuple of (xarray.Dataset, Metrics)
        Time histories (``time`` [s], ``spacecraft``, ``axis``, ...) with provenance attributes, and the
        scalar metrics (a dict; their units in ``metrics.units``).

    Examples
    --------
    >>> from formation_ftc.api import simulate_with_metrics
    >>> ds, metrics = simulate_with_metrics("cw-free-drift")
    >>> float(ds.time[-1]), sorted(metrics)[:1], metrics.units["delta_v_total"]
    (5840.0, ['control_effort_sc1'], 'm s-1')
    """
    from formation_ftc.sim.programs import jitted_run

    if not isinstance(scenario, ScenarioBase):
        scenario = load_scenario(scenario)
    loop = build_loop(scenario)
    out = jitted_run(loop)(loop)
    ds, metrics = finish_run(scenario, loop, out, raise_on_divergence=raise_on_divergence)
    return ds, Metrics(metrics, metric_units(ds))


def simulate(scenario: ScenarioBase | str | Path):
    """Run one scenario and return its ``xarray.Dataset`` (metrics in ``attrs['metrics_json']``).

    Parameters
    ----------
    scenario : ScenarioBase, str or Path
        A loaded scenario, a built-in name or a TOML path.

    Returns
    -------
    xarray.Dataset
        As :func:`simulate_with_metrics`; a diverged run raises
        :class:`~formation_ftc.sim.engine.SimulationDiverged` (its ``partial`` holds what was computed).

    Examples
    --------
    >>> from formation_ftc.api import simulate
    >>> ds = simulate("cw-free-drift")
    >>> ds.position.dims
    ('time', 'spacecraft', 'axis')
    """
    return simulate_with_metrics(scenario)[0]


def result_metrics(ds) -> dict[str, float]:
    """Scalar metrics stored in a result dataset.

    Parameters
    ----------
    ds : xarray.Dataset
        A result of :func:`simulate` (or read back from ``result.nc``).

    Returns
    -------
    dict of str to float
        Metric name -> value (SI units: :func:`metric_units`).

    Examples
    --------
    >>> from formation_ftc.api import result_metrics, simulate
    >>> round(result_metrics(simulate("cw-free-drift"))["delta_v_total"], 6)
    0.0
    """
    return json.loads(ds.attrs.get("metrics_json", "{}"))


def check(scenario: ScenarioBase | str | Path) -> Conditions:
    """Evaluate the stability / design conditions the scenario's method declares.

    Parameters
    ----------
    scenario : ScenarioBase, str or Path
        A loaded scenario, a built-in name or a TOML path.

    Returns
    -------
    Conditions
        A list of :class:`~formation_ftc.registry.Condition`, one per condition: name, value,
        requirement, whether it holds, whether it is required (shown as a table in Jupyter).

    Examples
    --------
    >>> from formation_ftc.api import check
    >>> all(c.holds for c in check("cw-pd-fault") if c.required)
    True
    """
    if not isinstance(scenario, ScenarioBase):
        scenario = load_scenario(scenario)
    method = get_method(scenario.scenario.method)
    return Conditions(method.check(scenario) if method.check else [])


def _metric_units(declared: Iterable[Any], count: int) -> dict[str, str]:
    """UDUNITS unit of each metric the loop's ``declared`` metrics return (``"1"`` for dimensionless),
    those declared per spacecraft by name: ``name_sc1``, ..., ``name_sc{count}``."""
    out = {}
    for m in declared or ():
        each = getattr(m, "spacecraft", None) == "each"
        names = [f"{m.name}_sc{i + 1}" for i in range(count)] if each else [m.name]
        out.update(dict.fromkeys(names, str(getattr(m, "units", "") or "1")))
    return out


def metric_units(ds) -> dict[str, str]:
    """Units of the scalar metrics stored in a result dataset (``{metric: UDUNITS string}``).

    Parameters
    ----------
    ds : xarray.Dataset
        A result of :func:`simulate`.

    Returns
    -------
    dict of str to str
        Metric name -> UDUNITS unit (``"1"`` for dimensionless).

    Examples
    --------
    >>> from formation_ftc.api import metric_units, simulate
    >>> metric_units(simulate("cw-free-drift"))["delta_v_total"]
    'm s-1'
    """
    return json.loads(ds.attrs.get("metric_units_json", "{}"))


def save_result(
    ds, out_dir: str | Path, metrics: Mapping[str, float] | None = None
) -> dict[str, Path]:
    """Write ``result.nc`` (NetCDF via h5netcdf) and ``metrics.json`` into ``out_dir``.

    Both files are first written under temporary names and only then renamed into place, so a failure
    while writing either leaves the previous pair untouched (never a new result with old metrics).
    ``formation-ftc run`` additionally writes into a temporary sibling directory that replaces
    ``out_dir`` as a whole.

    Parameters
    ----------
    ds : xarray.Dataset
        A result of :func:`simulate`.
    out_dir : str or Path
        Directory to write into (created if missing).
    metrics : Mapping of str to float, optional
        Metrics to write (default: those stored in ``ds``).

    Returns
    -------
    dict of str to Path
        ``{"result": .../result.nc, "metrics": .../metrics.json}``.

    Examples
    --------
    >>> import tempfile
    >>> from formation_ftc.api import save_result, simulate
    >>> with tempfile.TemporaryDirectory() as d:
    ...     paths = save_result(simulate("cw-free-drift"), d)
    ...     sorted(p.name for p in paths.values())
    ['metrics.json', 'result.nc']
    """
    from formation_ftc.atomic import temporary_name
    from formation_ftc.cf import write_netcdf

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    nc, mj = out_dir / "result.nc", out_dir / "metrics.json"
    tmp_nc, tmp_mj = temporary_name(nc), temporary_name(mj)
    m: dict[str, Any] = dict(metrics if metrics is not None else result_metrics(ds))
    m["scenario"] = ds.attrs.get("scenario_name", "")
    units = metric_units(ds)
    if units:
        m["units"] = {k: units.get(k, "") for k in m if k not in ("scenario", "units")}
    try:
        write_netcdf(ds, tmp_nc)  # CF-1.10, netCDF4-classic compatible
        tmp_mj.write_text(json.dumps(m, indent=2, sort_keys=True))
        tmp_mj.replace(mj)
        tmp_nc.replace(nc)
    finally:
        for t in (tmp_nc, tmp_mj):
            t.unlink(missing_ok=True)
    return {"result": nc, "metrics": mj}
