"""CF-1.10 conventions for result datasets: global attributes, per-variable metadata, attribute hygiene.

``formation_ftc.api.finish_run`` calls :func:`apply_cf` on every result, and the campaign store on every
trace, so every NetCDF file the package writes (``result.nc``, ``traces/run-NNNNNN.nc``, both through
:func:`write_netcdf`) opens in any CF-aware tool (xarray, Panoply, ncview, ``nccopy -k classic``) and
passes the CF checker (``cfchecks``) without errors:

* global attributes ``Conventions``, ``title``, ``institution``, ``source``, ``history``, ``references``,
  next to the provenance (``version_<package>``, ``git_commit``, ``created_utc``, ``scenario_name``,
  ``seed``, ...);
* every data variable and coordinate carries ``units`` (a UDUNITS string, ``"1"`` when dimensionless)
  and ``long_name``; vectors keep the ``frame`` their component declared;
* ``time`` is the time since the start of the simulation in seconds (``units = "s"``, ``long_name =
  "time since the start of the simulation"``). A simulation has no calendar epoch, and CF (section 4.4)
  makes a variable a *time coordinate* only with units ``<unit> since <reference time>``; a duration in
  ``s`` is an ordinary coordinate, so it must not claim ``standard_name = "time"`` or ``axis = "T"``
  (either makes CF tools require a reference time). Any variable whose units have no reference time
  loses those two attributes. Inventing an epoch (``seconds since 1970-01-01``) would put a false date
  on every sample;
* no coordinate variable has a ``_FillValue`` (CF 2.5.1: coordinates have no missing values);
* attribute names contain only letters, digits and underscores (``version_formation-ftc`` is written
  ``version_formation_ftc``), and attribute values are strings or numbers (netCDF4-classic compatible:
  booleans become 0/1, ``None`` becomes ``""``, anything nested becomes its JSON text).

Text coordinates (``axis``, ``pair``, ...) are stored as character arrays named after their dimension,
so xarray reads them back as coordinates; the CF checker warns about those ("possible incorrect
declaration of a coordinate variable", CF 5), which is the price of the round trip.
"""

from __future__ import annotations

import json
import re
from typing import Any

import numpy as np

__all__ = [
    "CONVENTIONS",
    "ELAPSED_TIME",
    "apply_cf",
    "cf_problems",
    "clean_attrs",
    "netcdf_bytes",
    "write_netcdf",
    "MIXED_UNITS_NOTE",
]

CONVENTIONS = "CF-1.10"
ELAPSED_TIME = "time since the start of the simulation"
MIXED_UNITS_NOTE = (
    "components carry different units (see component_units); the variable as a whole is "
    "stored with units '1'"
)

_COORD_DEFAULTS: dict[str, tuple[str, str]] = {
    "time": ("s", ELAPSED_TIME),
    "spacecraft": ("1", "spacecraft number (1-based)"),
    "axis": ("1", "vector component"),
    "component": ("1", "state component"),
    "quaternion_component": ("1", "quaternion component"),
    "wrench_component": ("1", "force/torque component"),
    "pair": ("1", "pair of consecutive spacecraft"),
    "link": ("1", "communication link (sender-receiver)"),
}

_NAME_BAD = re.compile(r"[^A-Za-z0-9_]")


def _attr_name(key: str) -> str:
    name = _NAME_BAD.sub("_", str(key))
    return name if re.match(r"[A-Za-z]", name) else "a_" + name


def _attr_value(v: Any) -> str | int | float | np.integer | np.floating | np.ndarray:
    if v is None:
        return ""
    if isinstance(v, bool | np.bool_):
        return int(v)
    if isinstance(v, str | int | float | np.integer | np.floating):
        return v
    if isinstance(v, np.ndarray) and v.dtype.kind in "iuf" and v.ndim == 1:
        return v
    if (
        isinstance(v, list | tuple)
        and v
        and all(isinstance(x, int | float) and not isinstance(x, bool) for x in v)
    ):
        return np.asarray(v)
    try:
        return json.dumps(v, default=str)
    except TypeError:
        return str(v)


def clean_attrs(attrs: dict[str, Any]) -> dict[str, Any]:
    """Attributes with netCDF-safe names (``[A-Za-z][A-Za-z0-9_]*``) and netCDF4-classic values."""
    return {_attr_name(k): _attr_value(v) for k, v in attrs.items()}


def _title(scenario_name: str, method: str, description: str) -> str:
    head = f"formation-ftc simulation of scenario '{scenario_name}' (method {method})"
    return f"{head}: {description}" if description else head


def apply_cf(
    ds,
    *,
    scenario_name: str = "",
    method: str = "",
    description: str = "",
    references: str = "",
    created_utc: str = "",
    version: str = "",
) -> Any:
    """Make ``ds`` a CF-1.10 result in place (and return it).

    Parameters
    ----------
    ds : xarray.Dataset
        A result as ``ClosedLoop.dataset`` builds it (declared signals with units, long_name, frame).
    scenario_name, method, description : str
        Used in the ``title`` global attribute.
    references : str
        Publications the method implements (``references`` global attribute).
    created_utc : str
        ISO 8601 creation time, first entry of ``history``.
    version : str
        formation-ftc version named in ``source``.
    """
    for name in list(ds.variables):
        var = ds[name] if name in ds.data_vars else ds.coords[name]
        attrs = dict(var.attrs)
        default_units, default_long = _COORD_DEFAULTS.get(
            str(name), ("1", str(name).replace("_", " "))
        )
        units = str(attrs.get("units", "") or "").strip()
        if not units or units == "-":
            units = default_units
        if "," in units:  # a stacked vector whose components have different units ("m, m s-1")
            attrs["component_units"] = units
            attrs["comment"] = MIXED_UNITS_NOTE
            units = "1"
        attrs["units"] = units
        long_name = str(attrs.get("long_name", "") or "").strip()
        if not long_name or (name == "time" and long_name == "time"):
            attrs["long_name"] = default_long
        if " since " not in units:  # not a CF time coordinate (see the module docstring)
            if attrs.get("standard_name") in ("time", "forecast_reference_time"):
                del attrs["standard_name"]
            if attrs.get("axis") == "T":
                del attrs["axis"]
        var.attrs.clear()
        var.attrs.update(clean_attrs(attrs))
    attrs = dict(ds.attrs)
    history = f"{created_utc} formation-ftc {version} simulate {scenario_name}".strip()
    attrs.update(
        Conventions=CONVENTIONS,
        title=_title(scenario_name, method, description),
        institution=str(attrs.get("institution", "")) or "formation-ftc (open-source toolkit)",
        source=f"formation-ftc {version}, method {method}, JAX float64 fixed-step simulation".strip(),
        history=history if not attrs.get("history") else f"{attrs['history']}\n{history}",
        references=references
        or str(attrs.get("references", ""))
        or "see the method's documentation",
    )
    ds.attrs.clear()
    ds.attrs.update(clean_attrs(attrs))
    return ds


def cf_problems(ds) -> list[str]:
    """What keeps ``ds`` from being a CF-1.10 / netCDF4-classic compatible result (empty when none)."""
    out = []
    for key in ("Conventions", "title", "institution", "source", "history", "references"):
        if not isinstance(ds.attrs.get(key), str) or not ds.attrs[key]:
            out.append(f"global attribute {key!r} missing")
    items = [("<global>", ds.attrs)] + [(str(n), ds.variables[n].attrs) for n in ds.variables]
    for where, attrs in items:
        for k, v in attrs.items():
            if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", str(k)):
                out.append(f"{where}: attribute name {k!r} is not netCDF-safe")
            ok = isinstance(v, str | int | float | np.integer | np.floating) and not isinstance(
                v, bool | np.bool_
            )
            ok = ok or (isinstance(v, np.ndarray) and v.dtype.kind in "iuf" and v.ndim == 1)
            if not ok:
                out.append(f"{where}: attribute {k!r} has type {type(v).__name__}")
        if where != "<global>":
            for k in ("units", "long_name"):
                if not isinstance(attrs.get(k), str) or not attrs[k]:
                    out.append(f"{where}: no {k}")
    return out


def _classic_attrs(attrs: dict[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in clean_attrs(attrs).items():
        if isinstance(
            v, str
        ):  # NC_CHAR, not NC_STRING (h5py writes np.bytes_ as a fixed-length string)
            out[k] = np.bytes_(v.encode("utf-8"))
        elif isinstance(v, int | np.integer):
            out[k] = np.int32(v) if -(2**31) <= int(v) < 2**31 else float(v)
        elif isinstance(v, np.ndarray) and v.dtype.kind in "iu":
            out[k] = (
                v.astype(np.int32) if v.size == 0 or np.abs(v).max() < 2**31 else v.astype(float)
            )
        else:
            out[k] = v
    return out


def classic_compatible(ds):
    """A copy of ``ds`` whose NetCDF file is netCDF4-classic compatible (``nccopy -k classic`` converts it).

    Text attributes are written as character arrays (``NC_CHAR``) rather than variable-length strings,
    integer attributes and 64-bit integer variables as 32-bit integers, and text coordinates as
    character arrays; coordinates get no ``_FillValue``. Values read back with xarray are unchanged (text
    stays text).
    """
    out = ds.copy(deep=False)
    out.attrs = _classic_attrs(ds.attrs)
    for name in list(out.variables):
        var = out.variables[name]
        var.attrs = _classic_attrs(ds.variables[name].attrs)
        if (
            name in out.coords
        ):  # CF: no missing values in coordinates (xarray adds a NaN fill to floats)
            var.encoding["_FillValue"] = None
        if var.dtype.kind in "UO":  # char array + _Encoding (fixed by ``fix_text_encoding_attrs``)
            var.encoding["dtype"] = "S1"
        elif var.dtype.kind in "iu" and var.dtype.itemsize > 4:
            var.encoding["dtype"] = "i4"
        elif var.dtype.kind == "b":
            var.encoding["dtype"] = "i1"
    return out


def fix_text_encoding_attrs(path) -> None:
    """Rewrite the ``_Encoding`` attributes xarray puts on text variables as ``NC_CHAR`` (h5py); ``path``
    is a file name or a file-like object holding the file."""
    import h5py

    with h5py.File(path, "r+") as f:
        for obj in f.values():
            if isinstance(obj, h5py.Dataset) and "_Encoding" in obj.attrs:
                value = obj.attrs["_Encoding"]
                value = value.decode() if isinstance(value, bytes) else str(value)
                del obj.attrs["_Encoding"]
                obj.attrs["_Encoding"] = np.bytes_(value.encode("ascii"))


def netcdf_bytes(ds) -> memoryview:
    """The NetCDF-4 file of ``ds`` (h5netcdf; netCDF4-classic compatible, CF-readable), built in memory.

    HDF5 writes nothing to disk here: on a full disk, HDF5 errors while h5py releases a half-written
    file have crashed the interpreter (a segmentation fault), so the file is assembled in a
    ``BytesIO`` and written with plain Python I/O, which raises ``OSError`` like any other write.

    Parameters
    ----------
    ds : xarray.Dataset
        The dataset (after :func:`apply_cf`).

    Returns
    -------
    memoryview
        The file's bytes.

    Examples
    --------
    >>> import numpy as np
    >>> import xarray as xr
    >>> from formation_ftc.cf import netcdf_bytes
    >>> data = netcdf_bytes(xr.Dataset({"x": ("t", np.arange(3.0))}))
    >>> bytes(data[:8])  # the HDF5 signature
    b'\\x89HDF\\r\\n\\x1a\\n'
    """
    import io

    buf = io.BytesIO()
    classic_compatible(ds).to_netcdf(buf, engine="h5netcdf")
    fix_text_encoding_attrs(buf)
    return buf.getbuffer()


def write_netcdf(ds, path) -> None:
    """Write ``ds`` to ``path`` as a NetCDF-4 file (h5netcdf) that is netCDF4-classic compatible and
    CF-readable: built in memory (:func:`netcdf_bytes`), then written with plain Python I/O (a full disk
    raises ``OSError``: ``ENOSPC``)."""
    data = netcdf_bytes(ds)
    with open(path, "wb") as f:
        f.write(data)
