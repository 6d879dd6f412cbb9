"""Results people can open anywhere: CF-1.10 attributes and UDUNITS units on every built-in scenario's
result, netCDF4-classic compatibility (``nccopy -k classic`` when netcdf-bin is installed, else the
equivalent attribute/dtype check), and metric units in metrics.json."""

from __future__ import annotations

import json
import re
import shutil
import subprocess

import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc import api

# A strict UDUNITS-like grammar: space-separated products of known unit symbols with optional integer
# exponents ("m s-2", "N m", "N2 m2 s", "rad s-1"), or "1" for dimensionless. Written independently of
# the package: what it rejects ("-", "m/s", "m, m s-1", "N per unit gain", "deg/s") is what CF tools reject.
_SYMBOLS = {"m", "s", "kg", "N", "rad", "sr", "K", "W", "J", "Hz", "km", "ms", "A", "V", "T", "Pa"}
_TOKEN = re.compile(r"(?P<sym>[A-Za-z]+)(?P<exp>-?[1-9][0-9]*)?")


def udunits_ok(units: object) -> bool:
    if not isinstance(units, str):
        return False
    if units == "1":
        return True
    parts = units.split(" ")
    if not parts or any(not p for p in parts):
        return False
    for p in parts:
        m = _TOKEN.fullmatch(p)
        if m is None or m["sym"] not in _SYMBOLS:
            return False
    return True


def test_udunits_validator_rejects_what_cf_tools_reject():
    for good in ("1", "m", "m s-1", "m s-2", "N m", "N2 m2 s", "rad s-1", "kg", "m2 s-3"):
        assert udunits_ok(good), good
    for bad in ("-", "", "m/s", "m, m s-1", "N per unit gain", "deg/s", "m  s", "m s-0", None, 1):
        assert not udunits_ok(bad), bad


_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*")


def _classic_attr_ok(v) -> bool:
    if isinstance(v, bool | np.bool_) or v is None:
        return False
    if isinstance(v, str | float | np.floating):
        return True
    if isinstance(v, int | np.integer):
        return -2**31 <= int(v) < 2**31
    return isinstance(v, np.ndarray) and v.ndim == 1 and v.dtype.kind in "if" and v.dtype.itemsize <= 8


def _short(name: str) -> dict:
    scn = ftc.load_scenario(name)
    dt, k = float(scn.simulation.dt), int(scn.simulation.record_every)
    return {"simulation.horizon": 2 * k * dt}


@pytest.mark.parametrize("name", sorted(api.list_scenarios()))
def test_every_builtin_result_is_cf_and_classic_compatible(name, tmp_path):
    import xarray as xr

    scn = ftc.load_scenario(name, overrides=_short(name))
    ds, metrics = api.simulate_with_metrics(scn)
    api.save_result(ds, tmp_path, metrics)
    with xr.open_dataset(tmp_path / "result.nc", engine="h5netcdf") as back:
        back = back.load()
    # global attributes (CF-1.10 section 2.6)
    assert back.attrs["Conventions"] == "CF-1.10"
    for key in ("title", "institution", "source", "history", "references"):
        assert isinstance(back.attrs.get(key), str) and back.attrs[key].strip(), key
    assert name in back.attrs["title"] and name in back.attrs["history"]
    # every variable and coordinate: UDUNITS units and a long_name; vectors a frame
    assert set(back.data_vars) == set(ds.data_vars) and len(back.data_vars) > 0
    for vname in back.variables:
        attrs = back[vname].attrs
        assert udunits_ok(attrs.get("units")), (vname, attrs.get("units"))
        assert isinstance(attrs.get("long_name"), str) and attrs["long_name"].strip(), vname
        if vname in ds.variables:  # the frame a component declares for a vector survives the file
            assert attrs.get("frame") == ds[vname].attrs.get("frame"), vname
    # values survive the trip, text coordinates stay text
    for vname in ds.data_vars:
        np.testing.assert_array_equal(back[vname].values, ds[vname].values)
    for cname in back.coords:
        if back[cname].dtype.kind in "UOS":
            assert all(isinstance(x, str) for x in back[cname].values), cname
            assert list(back[cname].values) == [str(x) for x in ds[cname].values], cname
    # netCDF4-classic compatible attributes: safe names, strings or 32-bit numbers
    items = [("<global>", back.attrs)] + [(v, back[v].attrs) for v in back.variables]
    for where, attrs in items:
        for k, v in attrs.items():
            assert _NAME.fullmatch(k), (where, k)
            assert _classic_attr_ok(v), (where, k, type(v))
    for vname in back.variables:
        assert back[vname].dtype != np.int64 or back[vname].encoding.get("dtype") != np.int64, vname
    if shutil.which("nccopy"):
        proc = subprocess.run(["nccopy", "-k", "classic", str(tmp_path / "result.nc"), str(tmp_path / "c.nc")],
                              capture_output=True, text=True, timeout=60)
        assert proc.returncode == 0, proc.stderr
    # metric units: a table next to the unchanged flat numbers
    mj = json.loads((tmp_path / "metrics.json").read_text())
    assert set(mj["units"]) == set(metrics)
    for k, v in metrics.items():
        assert mj[k] == pytest.approx(v, nan_ok=True) and udunits_ok(mj["units"][k]), k
        if k.startswith("delta_v"):  # a velocity increment, per spacecraft or in total
            assert mj["units"][k] == "m s-1", k


def test_campaign_store_opens_with_pandas_and_pyarrow_dataset_with_metric_units(tmp_path):
    import pandas as pd
    import pyarrow.dataset as pads

    from formation_ftc.campaign.runner import run_campaign

    raw = {"campaign": {"name": "cf", "base": "cw-pd-fault", "runs": 2, "seed": 3, "chunk_size": 2,
                        "metrics": ["max_position_error", "delta_v_total"]},
           "overrides": {"simulation.horizon": 2.0},
           "sample": {"controller.kp": {"dist": "uniform", "low": 1.0, "high": 3.0}}}
    results = run_campaign(raw, tmp_path / "c").results
    chunks = tmp_path / "c" / "chunks"
    df = pd.read_parquet(chunks)
    assert sorted(df["run_id"]) == sorted(results["run_id"]) and len(df) == 2
    np.testing.assert_array_equal(df.sort_values("run_id")["metric:max_position_error"].to_numpy(),
                                  results.sort_values("run_id")["metric:max_position_error"].to_numpy())
    schema = pads.dataset(chunks, format="parquet").schema
    # physical units of these metrics: a position error in metres, a velocity increment in m/s
    assert schema.field("metric:max_position_error").metadata[b"units"] == b"m"
    assert schema.field("metric:delta_v_total").metadata[b"units"] == b"m s-1"
    assert not (schema.field("run_id").metadata or {}).get(b"units")
