"""Third-party plug-ins register through the ``formation_ftc.plugins`` entry-point group.

The example package in ``tests/plugins/example_plugin`` (a new controller component registered as a composed controller type) is
installed with pip into a temporary directory -- not into the test environment -- and used from a
fresh interpreter whose ``PYTHONPATH`` holds that directory, as a user's ``pip install`` would.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

PLUGIN = Path(__file__).parent / "plugins" / "example_plugin"


def _install(tmp_path: Path) -> Path:
    target = tmp_path / "site"
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "install",
            "--quiet",
            "--no-deps",
            "--no-build-isolation",
            "--no-index",
            "--target",
            str(target),
            str(PLUGIN),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    if proc.returncode != 0:
        pytest.fail(f"pip could not install the example plug-in:\n{proc.stdout}\n{proc.stderr}")
    return target


def _python(code: str, site: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(site), FORMATION_FTC_JAX_CACHE="off")
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=300, env=env
    )


def test_example_plugin_registers_and_runs(tmp_path):
    site = _install(tmp_path)
    code = f"""
import json, numpy as np
import formation_ftc as ftc
from formation_ftc import registry
from formation_ftc.methods.composed import component_types
assert "composed" in registry.methods()          # the built-ins still load (and the plug-ins)
assert ("controller", "smooth-pd") in component_types("controller"), sorted(component_types())
scn = ftc.load_scenario({str(PLUGIN / "example.toml")!r})
ds, m = ftc.simulate_with_metrics(scn)
cmd = np.abs(ds.command.values)
print(json.dumps(dict(max_cmd=float(cmd.max()), final=float(np.abs(ds.position.values[-1]).max()),
                      errors=registry.PLUGIN_ERRORS)))
"""
    proc = _python(code, site)
    assert proc.returncode == 0, proc.stderr
    res = json.loads(proc.stdout.strip().splitlines()[-1])
    assert res["errors"] == {}
    # the plug-in's law saturates smoothly at 1 N per axis (the plain PD commands 20 N at 10 m)
    assert 0.5 < res["max_cmd"] < 1.0
    assert res["final"] < 10.0  # and it still drives the deputies towards the origin


def test_broken_plugin_is_reported_not_fatal(tmp_path):
    site = tmp_path / "site"
    dist = site / "broken_plugin-0.1.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: broken-plugin\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text("[formation_ftc.plugins]\nbroken = no_such_module_xyz\n")
    (dist / "RECORD").write_text("")
    code = """
from formation_ftc import registry
ms = registry.methods()
assert "composed" in ms
print(sorted(registry.PLUGIN_ERRORS))
"""
    proc = _python(code, site)
    assert proc.returncode == 0, proc.stderr
    assert "no_such_module_xyz" in proc.stdout
