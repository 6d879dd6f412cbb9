"""User-facing text cites only what resolves inside the repository.

Scanned: every string literal and docstring in ``src/`` (condition references, report rows and notes,
CLI messages, docstrings), the built-in scenario and campaign files, the CLI ``list`` output, the HTML
report built from the fake reproductions of ``tests/report``, README.md and ``docs/``. Each must

* cite erratum ids (``E000-04`` ...) only if ``docs/errata.md`` defines them,
* name repository paths (``docs/...``, ``benchmarks/...``, ``tests/...``) only if they exist,
* not cite working documents that are not part of the product (a specification, an architecture or
  performance note, an errata file outside ``docs/``, a reviewer's script).
"""

from __future__ import annotations

import io
import re
import sys
import tokenize
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "formation_ftc"

ERRATA_IDS = set(re.findall(r"\*\*(E\d{3}-\d{2})\*\*", (ROOT / "docs" / "errata.md").read_text()))
ID = re.compile(r"\bE\d{3}-\d{2}\b")
FORBIDDEN = re.compile(
    r"\bSPEC\b|SPEC\.md|ERRATA\.md|ARCHITECTURE\.md|PERFORMANCE\.md|reviewer'?s (reference )?script"
    r"|\breviewer's\b"
)
PATH = re.compile(r"(?<![\w/.])((?:docs|benchmarks|tests)/[\w./-]*\w\.(?:md|py|toml))")

#: Files outside the H2 brief (engine, methods, paper models/schemas/methods under rewrite) that still
#: cite working documents; their owners rewrite them. The test fails when an entry is no longer needed.
PENDING: set[str] = set()


def problems(text: str) -> list[str]:
    """Citations in ``text`` that do not resolve inside the repository."""
    out = [f"cites {m.group(0)!r} (not in the repository)" for m in FORBIDDEN.finditer(text)]
    out += [
        f"erratum {m.group(0)} not defined in docs/errata.md"
        for m in ID.finditer(text)
        if m.group(0) not in ERRATA_IDS
    ]
    out += [
        f"path {m.group(1)} does not exist"
        for m in PATH.finditer(text)
        if not (ROOT / m.group(1)).exists()
    ]
    return out


def python_strings(path: Path) -> str:
    """All string literals of a module (docstrings, messages, f-string parts), newline-joined."""
    toks = tokenize.generate_tokens(io.StringIO(path.read_text()).readline)
    kinds = {tokenize.STRING} | (
        {tokenize.FSTRING_MIDDLE} if hasattr(tokenize, "FSTRING_MIDDLE") else set()
    )
    return "\n".join(t.string for t in toks if t.type in kinds)


def _rel(p: Path) -> str:
    return p.relative_to(ROOT).as_posix()


def test_errata_file_defines_ids():
    assert len(ERRATA_IDS) >= 50
    assert problems("see E000-04 and E004-05 in docs/errata.md") == []
    assert problems("SPEC P0.4 reference") and problems("E999-01") and problems("docs/nothing.md")


def test_strings_and_docstrings_in_src_resolve():
    bad = {}
    for path in sorted(SRC.rglob("*.py")):
        found = problems(python_strings(path))
        if found:
            bad[_rel(path)] = found
    unexpected = {k: v[:3] for k, v in bad.items() if k not in PENDING}
    assert not unexpected, unexpected
    stale = sorted(k for k in PENDING if k not in bad and (ROOT / k).exists())
    assert not stale, f"no longer citing unresolved documents, remove from PENDING: {stale}"


@pytest.mark.parametrize(
    "path",
    sorted([*(SRC / "scenarios").glob("*.toml"), *(SRC / "campaign" / "builtin").glob("*.toml")]),
    ids=lambda p: p.name,
)
def test_scenario_and_campaign_files_resolve(path):
    assert problems(path.read_text()) == []


@pytest.mark.parametrize(
    "path", [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))], ids=lambda p: p.name
)
def test_readme_and_docs_resolve(path):
    assert problems(path.read_text()) == []


def test_cli_list_output_resolves(capsys):
    from formation_ftc.cli import main

    assert main(["list"]) == 0
    text = capsys.readouterr().out
    assert text.strip()
    assert problems(text) == []


def test_report_html_from_fakes_resolves(tmp_path):
    from rich.console import Console

    sys.path.insert(0, str(ROOT / "tests" / "report"))
    from report_fakes import ok_reproduction

    from formation_ftc.report.reproduce import reproduce

    out = tmp_path / "rep"
    reproduce(
        ["all"],
        out,
        progress=False,
        available={"alpha": ok_reproduction("alpha")},
        console=Console(file=io.StringIO()),
        include_3d=False,
    )
    page = (out / "index.html").read_text()
    assert "paper (where printed)" in page and "reference (how obtained)" in page
    assert problems(page) == []
