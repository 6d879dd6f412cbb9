"""The shipped composed-scenario schema (``formation_ftc/composed.schema.json``): equal to a fresh
generation, used only while its sources are unchanged, and what ``schema composed`` prints."""

from __future__ import annotations

import json
import subprocess
import sys

from formation_ftc import shipped_schema as shipped
from formation_ftc.methods.composed import composed_json_schema

REFRESH = "refresh it: python -m formation_ftc.shipped_schema"


def test_shipped_schema_is_current():
    schema = shipped.shipped_schema()
    assert schema is not None, f"composed.schema.json is stale (its sources changed); {REFRESH}"
    assert schema == composed_json_schema(), f"composed.schema.json differs; {REFRESH}"


def test_a_changed_source_falls_back_to_generation(tmp_path):
    data = json.loads(shipped.SCHEMA_FILE.read_text(encoding="utf-8"))
    data["fingerprint"] = "0" * 64  # as if a source had been edited since the file was written
    data["schema"] = {"title": "stale"}
    stale = tmp_path / "composed.schema.json"
    stale.write_text(json.dumps(data), encoding="utf-8")
    assert shipped.shipped_schema(stale) is None
    data["sources"] = ["no/such/module.py"]
    stale.write_text(json.dumps(data), encoding="utf-8")
    assert shipped.shipped_schema(stale) is None
    stale.write_text("{not json", encoding="utf-8")
    assert shipped.shipped_schema(stale) is None
    assert shipped.shipped_schema(tmp_path / "missing.json") is None


def test_a_new_home_makes_the_shipped_schema_stale(monkeypatch):
    """A home added to components/<kind>/ adds a type before anything imports it: the shipped schema
    is no longer used (and the test above says to refresh it)."""
    assert shipped.shipped_schema() is not None
    assert "components/controllers/lqr.py" in shipped._home_files()
    homes = shipped._home_files() + ["components/controllers/a_new_law.py"]
    monkeypatch.setattr(shipped, "_home_files", lambda: homes)
    assert shipped.shipped_schema() is None


def test_write_schema_file_round_trip(tmp_path):
    # in a fresh interpreter, as the refresh command runs: its sources are what generation imports
    target = tmp_path / "composed.schema.json"
    code = (
        "import sys; from pathlib import Path\n"
        "from formation_ftc.shipped_schema import write_schema_file\n"
        f"write_schema_file(Path({str(target)!r}))\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=300)
    data = json.loads(target.read_text(encoding="utf-8"))
    assert "components/controllers/pd.py" in data["sources"]
    assert "config/base.py" in data["sources"]
    assert shipped.shipped_schema(target) == composed_json_schema()


def test_schema_composed_prints_without_loading_catalogs():
    code = (
        "import sys, io\n"
        "from formation_ftc.cli import main\n"
        "out = io.StringIO(); real = sys.stdout; sys.stdout = out\n"
        "main(['schema', 'composed'])\n"
        "sys.stdout = real\n"
        "print(sorted(m for m in sys.modules if '.catalog_' in m or m in ('pydantic', 'jax._src')))\n"
        "print(out.getvalue())\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], check=True, capture_output=True, text=True, timeout=300
    ).stdout
    loaded, printed = out.split("\n", 1)
    assert loaded == "[]"
    schema = json.loads(printed)
    assert schema["title"] == "formation-ftc scenario (composed)"
    assert schema["properties"]["controller"] == composed_json_schema()["properties"]["controller"]
