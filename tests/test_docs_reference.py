"""The generated documentation pages (docs/hooks/formation_docs.py) cover what they claim to: every
scenario field of every method, every command of the command line, every paper."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

pytest.importorskip("mkdocs")

from formation_ftc.suggest import schema_paths  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def hook():
    spec = importlib.util.spec_from_file_location(
        "formation_docs", ROOT / "docs" / "hooks" / "formation_docs.py"
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_unit_extraction(hook):
    assert hook._unit_and_text("Position gain [N/m].") == ("N/m", "Position gain.")
    assert hook._unit_and_text("Desired position, expressions in t [s], i [m].") == (
        "m",
        "Desired position, expressions in t [s], i.",
    )
    assert hook._unit_and_text("No unit here.") == ("", "No unit here.")


def test_every_scenario_field_is_documented(hook):
    from formation_ftc.registry import methods

    pages = hook.scenario_reference()
    for name, method in methods().items():
        page = pages[f"reference/scenarios/{name}.md"]
        schema = method.schema.model_json_schema()
        for path in schema_paths(schema):
            head, _, leaf = path.rpartition(".")
            documented = f"| `{leaf}` |" in page or f"### `[{path}]`" in page
            assert documented, f"{name}: {path}"
        assert f"[`{name}`]({name}.md)" in pages["reference/scenarios/index.md"]


def test_cli_reference_has_every_command(hook):
    import argparse

    from formation_ftc.cli import build_parser

    text = hook.cli_reference()

    def names(p, prefix):
        for a in p._actions:
            if isinstance(a, argparse._SubParsersAction):
                for n, sub in a.choices.items():
                    yield f"{prefix} {n}"
                    yield from names(sub, f"{prefix} {n}")

    cmds = list(names(build_parser(), "formation-ftc"))
    assert "formation-ftc campaign run" in cmds and "formation-ftc schema" in cmds
    for c in cmds:
        assert f"`{c}`" in text, c
    assert "exit status:" in text and "examples:" in text


def test_papers_page_lists_every_reproduction_and_erratum(hook):
    from formation_ftc.registry import reproductions

    text = hook.papers_page()
    for paper, rep in reproductions().items():
        assert f"## `{paper}`" in text
        for eid, _ in rep.errata:
            assert f"`{eid}`" in text
