"""Results people can open anywhere: CF-1.10 attributes and UDUNITS units on every built-in scenario's
result, netCDF4-classic compatibility (``nccopy -k classic`` when netcdf-bin is installed, else the
equivalent attribute/dtype check), no error from the CF checker (``cfchecks``, when installed) on every
result and on a campaign trace, provenance read from the installed distributions, metric units
in metrics.json and units on every numeric Parquet column."""

from __future__ import annotations

import contextlib
import io
import json
import re
import shutil
import subprocess

import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc import api
from formation_ftc.cf import CONVENTIONS, ELAPSED_TIME

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
        return -(2**31) <= int(v) < 2**31
    return (
        isinstance(v, np.ndarray) and v.ndim == 1 and v.dtype.kind in "if" and v.dtype.itemsize <= 8
    )


def _short(name: str) -> dict:
    scn = ftc.load_scenario(name)
    dt, k = float(scn.simulation.dt), int(scn.simulation.record_every)
    return {"simulation.horizon": 2 * k * dt}


def _result_of_drawn_records(scn):
    """``api.finish_run`` on a run output of the loop's exact shapes and dtypes (``jax.eval_shape``: no
    compilation) filled with standard-normal draws (integers 0, no divergence): the result file the
    front end writes for this scenario, its values arbitrary -- a stricter round trip than a short
    run's, and a compiled program fewer per scenario (the real runs: ``RUN_END_TO_END``)."""
    import jax

    loop = api.build_loop(scn)
    shapes = jax.eval_shape(lambda p: dict(p.run()), loop)
    rng = np.random.default_rng(7)

    def draw(s):
        if np.issubdtype(s.dtype, np.floating):
            return rng.standard_normal(s.shape).astype(s.dtype)
        return np.zeros(s.shape, s.dtype)

    out = jax.tree_util.tree_map(draw, shapes)
    out["diverged_step"] = np.asarray(-1, shapes["diverged_step"].dtype)
    ds, metrics = api.finish_run(scn, loop, out)
    return ds, api.Metrics(metrics, api.metric_units(ds))


#: run end to end through ``simulate_with_metrics`` (the overrides of tests/methods/test_conformance.py's
#: short runs of the same scenarios, so that the two tests share the compiled programs)
RUN_END_TO_END = ("cw-free-drift", "gui2022-ilo")


@pytest.mark.parametrize(
    "name, run",
    [(n, False) for n in sorted(api.list_scenarios())] + [(n, True) for n in RUN_END_TO_END],
)
def test_every_builtin_result_is_cf_and_classic_compatible(name, run, tmp_path, cf_checker):
    import xarray as xr

    if run:
        scn = ftc.load_scenario(name)
        dt = float(scn.simulation.dt)
        scn = ftc.load_scenario(
            name, overrides={"simulation.horizon": 4 * dt, "simulation.record_every": 2}
        )
        ds, metrics = api.simulate_with_metrics(scn)
    else:
        ds, metrics = _result_of_drawn_records(ftc.load_scenario(name, overrides=_short(name)))
    api.save_result(ds, tmp_path, metrics)
    with xr.open_dataset(tmp_path / "result.nc", engine="h5netcdf") as back:
        back = back.load()
    # global attributes (CF-1.10 section 2.6)
    assert back.attrs["Conventions"] == "CF-1.10"
    for key in ("title", "institution", "source", "history", "references"):
        assert isinstance(back.attrs.get(key), str) and back.attrs[key].strip(), key
    assert name in back.attrs["title"] and name in back.attrs["history"]
    # time is the time since the start (no epoch): not a CF time coordinate, so no standard_name/axis
    assert back["time"].attrs["units"] == "s" and back["time"].attrs["long_name"] == ELAPSED_TIME
    assert "standard_name" not in back["time"].attrs and "axis" not in back["time"].attrs
    _assert_no_fill_value_on_coordinates(tmp_path / "result.nc", back)
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
    if (
        cf_checker is not None
    ):  # the CF checker when installed (test_cf_checker_* say when it is not)
        assert cf_checker(tmp_path / "result.nc") == []
    if shutil.which("nccopy"):
        proc = subprocess.run(
            ["nccopy", "-k", "classic", str(tmp_path / "result.nc"), str(tmp_path / "c.nc")],
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert proc.returncode == 0, proc.stderr
    # metric units: a table next to the unchanged flat numbers
    mj = json.loads((tmp_path / "metrics.json").read_text())
    assert set(mj["units"]) == set(metrics)
    for k, v in metrics.items():
        assert mj[k] == pytest.approx(v, nan_ok=True) and udunits_ok(mj["units"][k]), k
        if k.startswith("delta_v"):  # a velocity increment, per spacecraft or in total
            assert mj["units"][k] == "m s-1", k


def _assert_no_fill_value_on_coordinates(path, ds) -> None:
    import h5py

    with h5py.File(path, "r") as f:
        for cname in ds.coords:
            assert "_FillValue" not in f[cname].attrs, cname


def test_campaign_store_opens_with_pandas_and_pyarrow_dataset_with_metric_units(
    tmp_path, cf_checker
):
    import pandas as pd
    import pyarrow.dataset as pads
    import xarray as xr

    from formation_ftc.campaign.runner import run_campaign

    raw = {
        "campaign": {
            "name": "cf",
            "base": "cw-pd-fault",
            "runs": 2,
            "seed": 3,
            "chunk_size": 2,
            "metrics": ["max_position_error", "delta_v_total"],
        },
        "overrides": {"simulation.horizon": 20.0},
        "sample": {"controller.kp": {"dist": "uniform", "low": 1.0, "high": 3.0}},
        "traces": {"runs": [1]},
    }
    results = run_campaign(raw, tmp_path / "c").results
    # the trace is CF-1.10 with the provenance of a result.nc
    trace = tmp_path / "c" / "traces" / "run-000001.nc"
    with xr.open_dataset(trace, engine="h5netcdf") as tr:
        assert tr.attrs["Conventions"] == CONVENTIONS and "cw-pd-fault" in tr.attrs["title"]
        for key in (
            "git_commit",
            "version_formation_ftc",
            "version_cvxpy",
            "created_utc",
            "history",
            "source",
        ):
            assert isinstance(tr.attrs.get(key), str) and tr.attrs[key], key
        assert tr.attrs["scenario_name"] == "cw-pd-fault" and tr.attrs["method"] == "composed"
        assert (
            tr.attrs["seed"] == int(results.set_index("run_id").loc[1, "seed"])
            and tr.attrs["run_id"] == 1
        )
        assert (
            tr["time"].attrs["long_name"] == ELAPSED_TIME
            and "standard_name" not in tr["time"].attrs
        )
        for vname in tr.variables:
            assert udunits_ok(tr[vname].attrs.get("units")), vname
        _assert_no_fill_value_on_coordinates(trace, tr)
    if cf_checker is not None:
        assert cf_checker(trace) == []
    chunks = tmp_path / "c" / "chunks"
    df = pd.read_parquet(chunks)
    assert sorted(df["run_id"]) == sorted(results["run_id"]) and len(df) == 2
    np.testing.assert_array_equal(
        df.sort_values("run_id")["metric:max_position_error"].to_numpy(),
        results.sort_values("run_id")["metric:max_position_error"].to_numpy(),
    )
    schema = pads.dataset(chunks, format="parquet").schema
    # physical units of these metrics: a position error in metres, a velocity increment in m/s; an
    # identifier is dimensionless, a text column has no units
    assert schema.field("metric:max_position_error").metadata[b"units"] == b"m"
    assert schema.field("metric:delta_v_total").metadata[b"units"] == b"m s-1"
    assert schema.field("run_id").metadata[b"units"] == b"1"
    assert not (schema.field("status").metadata or {}).get(b"units")
    for path in sorted(chunks.glob("*.parquet")):
        assert_parquet_units(path)


def assert_parquet_units(path) -> None:
    """Units on every numeric column of a Parquet file, only as Arrow field metadata (see
    ``formation_ftc.parquet_units``): UDUNITS strings, or "unknown" for a sampled input."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from formation_ftc.parquet_units import UNKNOWN, read_units

    schema = pq.read_schema(path)
    units = read_units(path)
    for f in schema:
        numeric = pa.types.is_integer(f.type) or pa.types.is_floating(f.type)
        assert (f.name in units) == numeric, (path.name, f.name, f.type)
        if numeric:
            ok = udunits_ok(units[f.name]) or (
                f.name.startswith("input:") and units[f.name] == UNKNOWN
            )
            assert ok, (path.name, f.name, units[f.name])
    meta = schema.metadata or {}
    assert set(meta) <= {b"pandas"}, (
        path.name,
        set(meta),
    )  # no PANDAS_ATTRS or other file-level units
    assert not json.loads(meta.get(b"pandas", b"{}")).get("attributes"), (
        path.name
    )  # no DataFrame.attrs


# ------------------------------------------------------------------------------------- CF checker
# The checker's tables, offline (it downloads them otherwise): the package writes no standard_name,
# area_type or region, so empty tables suffice -- and any standard_name added later is reported as an
# error until it is listed here with its canonical units.
_CF_TABLES = {
    "standard-names.xml": "<standard_name_table><version_number>0</version_number>"
    "<last_modified>-</last_modified></standard_name_table>",
    "area-types.xml": "<area_type_table><version_number>0</version_number><date>-</date></area_type_table>",
    "regions.xml": "<standardized_region_list><version_number>0</version_number><date>-</date>"
    "</standardized_region_list>",
}


@pytest.fixture(scope="module")
def cf_checker(tmp_path_factory):
    """``run(path) -> [errors]``: the CF checker (PyPI ``cfchecker``) on one file; ``None`` when it is not
    usable (the reason in ``_CF_CHECKER_MISSING``).

    cfchecker 4.1 (the newest release) knows the rules up to CF-1.8 and refuses the name "CF-1.10"
    (error 2.6.1); registered here as a version, CF-1.10 files are checked against all the rules it has.
    """
    try:
        from cfchecker import cfchecks as cfc
    except Exception as exc:  # not installed, or cfunits without the UDUNITS-2 C library
        _CF_CHECKER_MISSING.append(
            f"CF checker not usable ({type(exc).__name__}: {exc}); install it with "
            f"`apt-get install libudunits2-0` and `pip install cfchecker` (.ci/run "
            f"does when it can)"
        )
        yield None
        return
    tables = tmp_path_factory.mktemp("cf-tables")
    for name, text in _CF_TABLES.items():
        (tables / name).write_text(f'<?xml version="1.0"?>\n{text}\n')
    version = cfc.CFVersion(CONVENTIONS)

    def run(path) -> list[str]:
        chk = cfc.CFChecker(
            cfStandardNamesXML=str(tables / "standard-names.xml"),
            cfAreaTypesXML=str(tables / "area-types.xml"),
            cfRegionNamesXML=str(tables / "regions.xml"),
            version=version,
            silent=True,
        )
        with contextlib.redirect_stdout(io.StringIO()):
            chk.checker(str(path))
        res = chk.all_results[str(path)]
        return [
            f"{where}: {msg}"
            for where, r in [("global", res["global"]), *res["variables"].items()]
            for msg in [*r.get("FATAL", []), *r.get("ERROR", [])]
        ]

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(cfc, "cfVersions", [*cfc.cfVersions, version])
        yield run


_CF_CHECKER_MISSING: list[str] = []


@pytest.fixture
def cfchecks(cf_checker):
    """The CF checker, or skip naming why it is not usable."""
    if cf_checker is None:
        pytest.skip(_CF_CHECKER_MISSING[0])
    return cf_checker


def test_cf_checker_runs_and_rejects_a_time_coordinate_without_epoch(tmp_path, cfchecks):
    """The CF checker the result and trace tests use (when installed) really runs: ``standard_name = time``
    with units ``s`` (no reference time) is a CF error (4.4), the one result.nc had."""
    import xarray as xr

    ds = xr.Dataset(
        {"x": ("time", np.zeros(3), {"units": "m", "long_name": "x"})},
        coords={"time": ("time", np.arange(3.0), {"units": "s", "standard_name": "time"})},
        attrs={"Conventions": CONVENTIONS},
    )
    ds.to_netcdf(tmp_path / "bad.nc", engine="h5netcdf")
    assert any("4.4" in e for e in cfchecks(tmp_path / "bad.nc"))


# ------------------------------------------------------------------------------------- provenance
def test_package_versions_come_from_the_distribution_that_installed_each_import_name(monkeypatch):
    import importlib.util
    from importlib import metadata

    from formation_ftc import provenance as prov

    installed = {"cvxpy-base": "1.5.0", "numpy": "2.0.0"}

    def version(dist):
        if dist in installed:
            return installed[dist]
        raise metadata.PackageNotFoundError(dist)

    monkeypatch.setattr(prov.metadata, "version", version)
    # read without scanning every installed distribution (0.6-1.9 s of a run)
    monkeypatch.setattr(prov.metadata, "packages_distributions", None)
    prov.package_versions.cache_clear()
    try:
        fake = prov.package_versions()
    finally:
        prov.package_versions.cache_clear()
    assert (
        fake["cvxpy"] == "1.5.0" and fake["numpy"] == "2.0.0" and fake["scipy"] == "not installed"
    )
    monkeypatch.undo()
    real = prov.package_versions()
    assert real["numpy"] == np.__version__ and real["formation-ftc"] == ftc.__version__
    if importlib.util.find_spec("cvxpy") is not None:  # installed as cvxpy or as cvxpy-base
        assert real["cvxpy"] != "not installed"
    assert prov.provenance()["version_cvxpy"] == real["cvxpy"]
