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
