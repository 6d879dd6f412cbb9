"""The page of a run (index.html) and its figures: ``formation-ftc run --figures`` draws them with the
result, a plain ``run`` does not (its page says how to), and ``formation-ftc plot DIR`` draws them later
from ``DIR/result.nc`` alone -- the same files, byte for byte."""

from __future__ import annotations

import json
import re
import shutil

import pytest

import formation_ftc as ftc
from formation_ftc.cli import main

#: positions, errors, commanded/applied control, fault + estimate: every standard figure
NAME = "compose-gui2022-on-li2020"
STANDARD = ("run_position.png", "run_tracking_error.png", "run_control.png", "run_fault.png")


@pytest.fixture(scope="module")
def drawn(tmp_path_factory):
    """A short run of NAME with ``--figures``: its directory and the bytes of every file it wrote."""
    sim = ftc.load_scenario(NAME).simulation
    horizon = 20 * sim.dt * sim.record_every
    out = tmp_path_factory.mktemp("page") / "run"
    argv = ["run", NAME, "--out", str(out), "--set", f"simulation.horizon={horizon!r}"]
    assert main([*argv, "--figures"]) == 0
    return out, {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}


def _refs(page: str) -> list[str]:
    return re.findall(r'(?:src|href)="([^"]+)"', page)


def test_run_writes_a_self_contained_page_with_the_standard_figures(drawn):
    out, _ = drawn
    page = (out / "index.html").read_text(encoding="utf-8")
    refs = _refs(page)
    for fig in STANDARD:
        assert (out / fig).is_file() and fig in refs, fig
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert len(pngs) > len(STANDARD) and set(pngs) <= set(refs)  # the method's figures too
    for ref in refs:  # nothing remote: every reference is a file of the run directory
        assert not re.match(r"^[a-z]+:|^//", ref), ref
        assert (out / ref).is_file(), ref
    assert "delta_v" in page and "m s-1" in page  # metrics with their units
    try:
        import plotly  # noqa: F401
    except ImportError:
        assert "plotly is not installed" in page
    else:
        assert 'id="trajectory3d"' in page and "plotly.min.js" in refs


def _positions():
    """A tiny result with 3-D positions of two spacecraft (what the 3-D view draws)."""
    import numpy as np
    import xarray as xr

    t = np.linspace(0.0, 10.0, 11)
    pos = np.stack([np.c_[t, 2 * t, -t], np.c_[-t, t, 0 * t]], axis=1)
    return xr.Dataset(
        {"position": (("time", "spacecraft", "axis"), pos, {"units": "m", "frame": "LVLH"})},
        coords={"time": t, "spacecraft": [1, 2], "axis": ["x", "y", "z"]},
        attrs={"scenario_name": "tiny <run>", "seed": 3},
    )


def test_runs_in_a_tree_share_one_plotly_copy(tmp_path):
    """Two run pages under a tree that holds plotly's bundle load that one copy (relative link); a
    page without a 3-D view writes none; a run on its own gets its copy next to the page."""
    import pytest

    pytest.importorskip("plotly")
    from plotly.offline import get_plotlyjs

    from formation_ftc.report.run_page import write_run_page

    tree = tmp_path / "tree"
    tree.mkdir()
    (tree / "plotly.min.js").write_text(get_plotlyjs(), encoding="utf-8")
    ds = _positions()
    for name in ("a", "b"):
        (tree / "runs" / name).mkdir(parents=True)
        page = write_run_page(tree / "runs" / name, ds, {"x": 1.0}, []).read_text()
        assert '<script src="../../plotly.min.js">' in page and 'id="trajectory3d"' in page
        assert "tiny &lt;run&gt;" in page  # escaped
    assert sorted(tree.rglob("plotly*.js")) == [tree / "plotly.min.js"]
    alone = tmp_path / "alone"
    alone.mkdir()
    page = write_run_page(alone, ds, {}, [], include_3d=False).read_text()
    assert "<script src" not in page and not list(alone.rglob("plotly*.js"))
    page = write_run_page(alone, ds, {}, []).read_text()
    assert '<script src="plotly.min.js">' in page and (alone / "plotly.min.js").is_file()


def test_plot_redraws_the_figures_of_a_run_from_its_files(drawn, tmp_path, capsys):
    """Figures deleted, ``plot`` draws them again from result.nc: the same bytes as those ``run``
    drew from the result in memory; the page lists them again, and a later ``run --out`` still
    recognises the directory as a run's (the new files are in its marker)."""
    src, files = drawn
    out = tmp_path / "run"
    shutil.copytree(src, out)
    for p in out.glob("*.png"):
        p.unlink()
    (out / "index.html").write_text("stale", encoding="utf-8")
    capsys.readouterr()
    assert main(["plot", str(out), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert (
        doc["kind"] == "run" and doc["format"] == "png" and doc["index"] == str(out / "index.html")
    )
    pngs = {n for n in files if n.endswith(".png")}
    assert {p.rsplit("/", 1)[-1] for p in doc["figures"]} == pngs
    for name in pngs:
        assert (out / name).read_bytes() == files[name], name
    page = (out / "index.html").read_text(encoding="utf-8")
    assert set(_refs(page)) == set(_refs(files["index.html"].decode()))
    assert not [p for p in out.iterdir() if p.name.startswith(".plot.tmp")]
    from formation_ftc.runout import is_run_result

    assert is_run_result(out)


def test_plot_needs_result_nc_only(drawn, tmp_path):
    """A copied result.nc alone in an empty directory: the same figures (here as SVG) and a page."""
    src, files = drawn
    out = tmp_path / "copy"
    out.mkdir()
    shutil.copy(src / "result.nc", out / "result.nc")
    assert main(["plot", str(out), "--format", "svg"]) == 0
    svgs = {p.name for p in out.glob("*.svg")}
    assert svgs == {n.replace(".png", ".svg") for n in files if n.endswith(".png")}
    assert not list(out.glob("*.png"))
    refs = _refs((out / "index.html").read_text(encoding="utf-8"))
    assert svgs <= set(refs)


def test_a_run_draws_no_figures_unless_asked(tmp_path, capsys):
    out = tmp_path / "plain"
    assert main(["run", "cw-free-drift", "--out", str(out), "--set", "simulation.horizon=10"]) == 0
    err = capsys.readouterr().err
    assert f"formation-ftc plot {out}" in err and re.search(r"in \d+\.\d\d s \(simulation", err)
    assert not list(out.glob("*.png")) and not (out / "plotly.min.js").exists()
    page = (out / "index.html").read_text(encoding="utf-8")
    assert "formation-ftc plot DIR" in page and "<img" not in page


@pytest.mark.parametrize("kind", ["missing", "empty", "file", "not a result"])
def test_plot_of_a_directory_without_results_exits_2(kind, tmp_path, capsys):
    d = tmp_path / "d"
    if kind == "empty":
        d.mkdir()
    elif kind == "file":
        d.write_text("x")
    elif kind == "not a result":
        d.mkdir()
        (d / "result.nc").write_bytes(b"not netcdf")
    assert main(["plot", str(d), "--json"]) == 2
    doc = json.loads(capsys.readouterr().out)
    assert doc["exit_code"] == 2 and str(d) in doc["error"]


def test_a_page_without_plotly_says_so(tmp_path, monkeypatch):
    """Without the ``interactive`` extra the page of a run drawn with figures says why it has no 3-D
    view (and renders: the template reads no field the note lacks)."""
    import builtins

    from formation_ftc.report.run_page import write_run_page

    real_import = builtins.__import__

    def no_plotly(name, *args, **kwargs):
        if name == "plotly" or name.startswith("plotly."):
            raise ImportError("no plotly here")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_plotly)
    page = write_run_page(tmp_path, _positions(), {"x": 1.0}, []).read_text()
    assert "plotly is not installed" in page and "<script src" not in page
    assert not list(tmp_path.glob("plotly*.js"))
