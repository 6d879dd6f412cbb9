"""A scenario compiled for the engine, and the generic path from a :class:`~.loop.ClosedLoop` to it.

:func:`compile_loop` derives everything a method used to write by hand -- the compile key (the loop's
tree definition), the dataset (from the declared :class:`~.components.Signal` s), the metrics (computed
inside the run), the divergence replay and the spacecraft axis of every state variable.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from dataclasses import dataclass
from typing import Any

import jax
import numpy as np

from formation_ftc.sim.components import KIND_SLOTS, structure_key
from formation_ftc.sim.metrics import metrics_dict

__all__ = ["Compiled", "compile_loop", "records_to_dataset"]

PyTree = Any


@dataclass(frozen=True)
class Compiled:
    """A scenario compiled for the engine.

    Attributes
    ----------
    run : pure function ``params -> RunOutput`` (see :mod:`formation_ftc.sim.engine`); jittable and
        vmappable over a leading batch axis of ``params``.
    params : pytree of float64/int arrays -- everything numeric a campaign may vary (for a
        :class:`~.loop.ClosedLoop`, the loop itself).
    static_key : hashable; two scenarios with equal keys share one compiled ``run`` (and can be batched).
    dt, record_every : step [s] and decimation used to map records to time.
    to_dataset : ``(out, n_records) -> xarray.Dataset`` from one run's numpy output (records trimmed
        to ``n_records``); the generic layer adds provenance attributes.
    metrics : ``out -> {name: float}`` scalar metrics of one run (numpy side).
    make_step : ``params -> step(k, state)``; used to diagnose a divergence (replays one step).
    spacecraft_axis : ``variable name -> axis index of the spacecraft dimension or None``.
    """

    run: Callable[[PyTree], Any]
    params: PyTree
    static_key: Hashable
    dt: float
    record_every: int
    to_dataset: Callable[[dict, int], Any]
    metrics: Callable[[dict], dict[str, float]]
    make_step: Callable[[PyTree], Callable] | None = None
    spacecraft_axis: Callable[[str], int | None] | None = None
    t0: float = 0.0


def records_to_dataset(loop, records: dict, n_records: int, attrs: dict | None = None):
    """Records of a run of ``loop`` -> ``xarray.Dataset`` with every declared signal, its dims, units,
    long_name and frame; time [s] from ``t0 + j * dt * record_every``.

    Parameters
    ----------
    loop : ClosedLoop
        The loop whose signals were recorded.
    records : dict of str to array
        Recorded signals (leading axis = record index; SI units).
    n_records : int
        Records to keep.
    attrs : dict, optional
        Dataset attributes.

    Returns
    -------
    xarray.Dataset
        Every recorded declared signal with its dims, units, long_name and frame.

    Raises
    ------
    ValueError
        A record whose shape does not match its declared dims.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.controllers.none import ZeroController
    >>> from formation_ftc.components.plants.clohessy_wiltshire import ClohessyWiltshirePlant
    >>> from formation_ftc.sim.loop import ClosedLoop
    >>> plant = ClohessyWiltshirePlant(mean_motion=np.float64(1e-3), mass=np.array([10.0]),
    ...                                initial_state_lvlh=np.array([[100.0, 0.0, 0.0, 0.0, 0.0, 0.0]]))
    >>> loop = ClosedLoop(plant=plant, controller=ZeroController(count=1), dt=10.0, n_steps=2)
    >>> from formation_ftc.sim.compiled import records_to_dataset
    >>> ds = records_to_dataset(loop, {"position": np.ones((3, 1, 3))}, n_records=3)
    >>> ds["position"].dims, ds["position"].attrs["units"], ds["position"].attrs["frame"]
    (('time', 'spacecraft', 'axis'), 'm', 'LVLH')
    >>> ds["time"].values
    array([ 0., 10., 20.])
    """
    import pandas as pd
    import xarray as xr
    from xarray.indexes import PandasIndex

    time = loop.t0 + np.arange(n_records) * loop.dt * loop.record_every
    coords: dict[str, Any] = {
        "time": ("time", time, {"units": "s", "long_name": "time", "standard_name": "time"}),
        "spacecraft": (
            "spacecraft",
            np.arange(1, loop.count + 1),
            {"long_name": "spacecraft number (1-based)", "units": "1"},
        ),
    }
    # declared coordinates first (they win over the default axis labels)
    for comp in (getattr(loop, slot) for slot in KIND_SLOTS):
        for name, values in comp.coords().items():
            coords.setdefault(name, (name, list(values)))
    data = {}
    for sig in loop.signals():
        if sig.name not in records:
            continue
        arr = np.asarray(records[sig.name])[:n_records]
        dims = ("time",) + tuple(sig.dims)
        if arr.ndim != len(dims):
            raise ValueError(
                f"signal {sig.name!r}: declared dims {dims} but recorded shape {arr.shape}"
            )
        meta = {"units": sig.units, "long_name": sig.long_name}
        if sig.frame:
            meta["frame"] = sig.frame
        data[sig.name] = (dims, arr, meta)
        for d, n in zip(dims, arr.shape, strict=True):
            if d == "axis" and "axis" not in coords:
                coords["axis"] = (
                    "axis",
                    ["x", "y", "z"][:n] if n <= 3 else list(range(n)),
                    {"long_name": "vector component"},
                )
    used = {d for v in data.values() for d in v[0]}
    coords = {k: v for k, v in coords.items() if k in used}
    # numpy variables and pandas indexes, which xarray takes as they are: from anything else it
    # first asks whether it is a dask array, which imports dask when dask is installed (0.2 s)
    variables, indexes = {}, {}
    for name, (dims, values, *meta) in coords.items():
        arr = np.asarray(values)
        index = PandasIndex(
            pd.Index(arr, dtype=object if arr.dtype.kind == "O" else None), name, arr.dtype
        )
        indexes[name] = index
        var = xr.Variable(dims, arr, meta[0] if meta else None, fastpath=True)
        variables.update(index.create_variables({name: var}))
    return xr.Dataset(
        {k: xr.Variable(d, np.asarray(v), m, fastpath=True) for k, (d, v, m) in data.items()},
        coords=xr.Coordinates(variables, indexes),
        attrs=attrs or {},
    )


def compile_loop(loop, dataset_attrs: dict | None = None) -> Compiled:
    """The engine's view of a closed loop: everything derived from the component declarations.

    Parameters
    ----------
    loop : ClosedLoop
        The loop (validated here).
    dataset_attrs : dict, optional
        Attributes of the datasets ``to_dataset`` builds.

    Returns
    -------
    Compiled
        ``run``, ``params`` (the loop), ``static_key`` (``("closed-loop", structure_key(loop))``), step
        [s], decimation, dataset and metric builders, divergence replay and spacecraft axes.

    Raises
    ------
    CompositionError
        Components that cannot work together (from ``loop.validate()``).

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.controllers.none import ZeroController
    >>> from formation_ftc.components.plants.clohessy_wiltshire import ClohessyWiltshirePlant
    >>> from formation_ftc.sim.loop import ClosedLoop
    >>> plant = ClohessyWiltshirePlant(mean_motion=np.float64(1e-3), mass=np.array([10.0]),
    ...                                initial_state_lvlh=np.array([[100.0, 0.0, 0.0, 0.0, 0.0, 0.0]]))
    >>> loop = ClosedLoop(plant=plant, controller=ZeroController(count=1), dt=10.0, n_steps=2)
    >>> from formation_ftc.sim.compiled import compile_loop
    >>> c = compile_loop(loop)
    >>> c.static_key[0], c.dt, c.record_every, c.params is loop
    ('closed-loop', 10.0, 1, True)
    >>> c.spacecraft_axis("0.plant.q")  # a leaf of the run's carry (state, accumulators), by path
    0
    """
    from formation_ftc.sim.loop import ClosedLoop

    loop.validate()

    def run(p: ClosedLoop):
        return p.run()

    def to_dataset(out, n_rec):
        return records_to_dataset(loop, out["records"], n_rec, dataset_attrs)

    def metrics(out):
        return metrics_dict(loop.metrics, out["metrics"])

    n = loop.count

    def spacecraft_axis(name: str) -> int | None:
        leaf = _leaf_by_name(loop, name)
        if leaf is None:
            return None
        shape = np.shape(leaf)
        if (
            "values" in name.split(".") and len(shape) >= 2 and shape[1] == n
        ):  # history ring buffers
            return 1
        return 0 if len(shape) >= 1 and shape[0] == n else None

    return Compiled(
        run=run,
        params=loop,
        static_key=("closed-loop", structure_key(loop)),
        dt=loop.dt,
        record_every=loop.record_every,
        to_dataset=to_dataset,
        metrics=metrics,
        make_step=lambda p: p.replay_step(),
        spacecraft_axis=spacecraft_axis,
        t0=loop.t0,
    )


def _leaf_by_name(loop, name: str):
    """Leaf of the run's carry named ``name`` (as the divergence diagnostic prints it), or None."""
    from formation_ftc.sim.engine import _path_name

    state = jax.eval_shape(lambda p: (p.initial_state(), None), loop)
    flat, _ = jax.tree_util.tree_flatten_with_path(state)
    for path, leaf in flat:
        if _path_name(path) == name:
            return leaf
    return None
