"""``formation-ftc run`` writes a self-contained index.html with the standard figures."""

from __future__ import annotations

import re

import formation_ftc as ftc
from formation_ftc.cli import main


def test_run_writes_a_self_contained_page_with_the_standard_figures(tmp_path):
    name = "compose-gui2022-on-li2020"  # positions, errors, commanded/applied control, fault + estimate
    sim = ftc.load_scenario(name).simulation
    horizon = 20 * sim.dt * sim.record_every
    out = tmp_path / "run"
    assert main(["run", name, "--out", str(out), "--set", f"simulation.horizon={horizon!r}"]) == 0
    page = (out / "index.html").read_text(encoding="utf-8")
    refs = re.findall(r'(?:src|href)="([^"]+)"', page)
    for fig in ("run_position.png", "run_tracking_error.png", "run_control.png", "run_fault.png"):
        assert (out / fig).is_file() and fig in refs, fig
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert set(pngs) <= set(refs)  # the method's own figures are on the page too
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
