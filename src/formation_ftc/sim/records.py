"""A run's records as an ``xarray.Dataset``.

:meth:`formation_ftc.sim.loop.ClosedLoop.dataset` uses it; it lives apart from the loop because it
imports xarray and pandas (numpy side only).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from formation_ftc.sim.components import KIND_SLOTS

__all__ = ["records_to_dataset"]


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
    >>> from formation_ftc.sim.records import records_to_dataset
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
    for sig in (s for s in loop.signals() if s.name in records):
        arr = np.asarray(records[sig.name])[:n_records]
        dims = ("time",) + tuple(sig.dims)
        if arr.ndim != len(dims):
            raise ValueError(
                f"signal {sig.name!r}: declared dims {dims} but recorded shape {arr.shape}"
            )
        meta = {"units": sig.units, "long_name": sig.long_name}
        if sig.frame:
            meta["frame"] = sig.frame
        data[sig.name] = xr.Variable(dims, arr, meta, fastpath=True)
        if "axis" in dims and "axis" not in coords:  # labelled by the first signal that has it
            n = arr.shape[dims.index("axis")]
            labels = ["x", "y", "z"][:n] if n <= 3 else list(range(n))
            coords["axis"] = ("axis", labels, {"long_name": "vector component"})
    used = {d for v in data.values() for d in v.dims}
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
    return xr.Dataset(data, coords=xr.Coordinates(variables, indexes), attrs=attrs or {})
