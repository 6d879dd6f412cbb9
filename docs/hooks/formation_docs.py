"""MkDocs hook: pages generated from the code at build time.

* ``reference/cli.md`` -- every command's ``--help`` from the argparse parser;
* ``reference/scenarios/<method>.md`` -- every scenario field (type, unit, range, default, meaning)
  from the method's pydantic schema, and ``reference/campaign-file.md`` from the campaign schema;
* ``papers.md`` -- what each paper's reproduction runs, its citation, errata and scenarios;
* ``examples/<name>.md`` -- every ``examples/NN_*.py`` (jupytext percent format) executed at reduced
  size in a subprocess (``docs/hooks/run_example.py``), with its printed output and figures.

Why a hook and not mkdocs-jupyter: the examples are plain scripts run exactly as a user runs them
(``python examples/NN.py``), no Jupyter kernel or nbconvert is needed, and one failing example fails
the strict build with its traceback.

Environment: ``FORMATION_FTC_DOCS_EXAMPLES=0`` skips executing the examples (pages show the code
only, for quick previews); ``FORMATION_FTC_DOCS_JOBS`` (default 2) examples run at once. Results are
cached in ``.cache/docs-examples`` keyed by the example's text and the package sources.
"""

from __future__ import annotations

import concurrent.futures
import hashlib
import json
import logging
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

from mkdocs.exceptions import PluginError
from mkdocs.structure.files import File, Files

log = logging.getLogger("mkdocs.hooks.formation_docs")
ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
CACHE = ROOT / ".cache" / "docs-examples"


# ------------------------------------------------------------------------------------------- helpers
def _gen(files: Files, config, path: str, content: str | bytes) -> None:
    existing = files.get_file_from_path(path)
    if existing is not None:
        files.remove(existing)
    files.append(File.generated(config, path, content=content))


def _cell(text: str) -> str:
    """Text with code spans for a Markdown table cell (pipes and newlines only)."""
    return str(text).replace("|", "\\|").replace("\n", " ")


def _md_escape(text: str) -> str:
    """Text for a Markdown table cell (no pipes, newlines or reference-link brackets)."""
    return (
        str(text)
        .replace("|", "\\|")
        .replace("\n", " ")
        .replace("[", "\\[")
        .replace("]", "\\]")
        .replace("*", "\\*")
        .replace("_", "\\_")
    )


# --------------------------------------------------------------------------------------------- CLI
def cli_reference() -> str:
    import argparse

    os.environ["COLUMNS"] = "100"  # argparse wraps at the terminal width: fix it for the page
    from formation_ftc.cli import build_parser

    lines = [
        "# Command-line reference",
        "",
        "Generated from the `formation-ftc` argument parser. Every command accepts `-q/--quiet` and "
        "`-v/--verbose`; `python -m formation_ftc` is the same program.",
        "",
    ]

    def walk(parser: argparse.ArgumentParser, name: str, level: int) -> None:
        lines.extend(
            [f"{'#' * level} `{name}`", "", "```text", parser.format_help().rstrip(), "```", ""]
        )
        for action in parser._actions:  # noqa: SLF001
            if isinstance(action, argparse._SubParsersAction):  # noqa: SLF001
                for sub_name, sub in action.choices.items():
                    walk(sub, f"{name} {sub_name}", min(level + 1, 4))

    walk(build_parser(), "formation-ftc", 2)
    return "\n".join(lines)


# -------------------------------------------------------------------------------- scenario schemas
def _resolve(node: dict, root: dict) -> dict:
    while "$ref" in node:
        target: Any = root
        for part in node["$ref"].lstrip("#/").split("/"):
            target = target[part]
        node = {**target, **{k: v for k, v in node.items() if k != "$ref"}}
    return node


def _type(node: dict, root: dict) -> str:
    node = _resolve(node, root)
    if "anyOf" in node or "oneOf" in node:
        return " or ".join(
            dict.fromkeys(_type(n, root) for n in node.get("anyOf", node.get("oneOf", [])))
        )
    if "enum" in node:
        return "one of " + ", ".join(f"`{v}`" for v in node["enum"])
    if "const" in node:
        return f"`{node['const']}`"
    t = node.get("type")
    if t == "array":
        items = node.get("prefixItems")
        inner = (
            _type(items[0], root)
            if items
            else _type(node.get("items", {}), root)
            if node.get("items")
            else "any"
        )
        n = node.get("minItems"), node.get("maxItems")
        size = f"{n[0]}" if n[0] is not None and n[0] == n[1] else ""
        return f"list of {size + ' ' if size else ''}{inner}".strip()
    if t == "object" and "properties" in node:
        return "table"
    if t == "object":
        return "table of values"
    return {
        "number": "number",
        "integer": "integer",
        "string": "string",
        "boolean": "boolean",
        "null": "none",
    }.get(str(t), str(t or "any"))


def _range(node: dict, root: dict) -> str:
    node = _resolve(node, root)
    parts = []
    for sub in node.get("anyOf", []):
        r = _range(sub, root)
        if r:
            parts.append(r)
    for key, op in (
        ("minimum", ">="),
        ("exclusiveMinimum", ">"),
        ("maximum", "<="),
        ("exclusiveMaximum", "<"),
    ):
        if key in node:
            parts.append(f"{op} {node[key]}")
    if node.get("type") == "array":
        lo, hi = node.get("minItems"), node.get("maxItems")
        if lo is not None and lo != hi:
            parts.append(f">= {lo} items")
        if hi is not None and lo != hi:
            parts.append(f"<= {hi} items")
        if node.get("items"):
            r = _range(node["items"], root)
            if r:
                parts.append(f"each {r}")
    return ", ".join(parts)


def _unit_and_text(description: str) -> tuple[str, str]:
    """``"Position gain [N/m]."`` -> ``("N/m", "Position gain.")``: the last bracketed unit."""
    d = description.strip()
    if "[" in d and "]" in d[d.rfind("[") :]:
        start = d.rfind("[")
        end = d.find("]", start)
        unit = d[start + 1 : end].strip()
        if unit and len(unit) <= 24 and " or " not in unit and "," not in unit:
            return unit, (d[:start].rstrip() + d[end + 1 :]).strip()
    return "", d


def _default(node: dict) -> str:
    if "default" not in node:
        return "**required**"
    v = node["default"]
    text = json.dumps(v) if not isinstance(v, str) else f'"{v}"'
    return f"`{_cell(text)}`" if len(text) <= 60 else f"`{_cell(text[:57])}...`"


def _section_rows(
    props: dict, root: dict, prefix: str, out: list[str], tables: list[tuple[str, dict]]
) -> None:
    for name, node in props.items():
        full = _resolve(node, root)
        path = f"{prefix}{name}"
        if full.get("type") == "object" and "properties" in full:
            tables.append((path, full))
            continue
        unit, text = _unit_and_text(full.get("description", node.get("description", "")))
        out.append(
            f"| `{path}` | {_cell(_type(node, root))} | {_md_escape(unit) or '-'} | "
            f"{_cell(_range(node, root)) or '-'} | {_default(full if 'default' in full else node)} | "
            f"{_md_escape(text)} |"
        )


def schema_tables(schema: dict) -> list[str]:
    """Markdown tables, one per TOML table (``[section]``), of a pydantic JSON Schema."""
    lines: list[str] = []
    queue: list[tuple[str, dict]] = []
    top_rows: list[str] = []
    _section_rows(schema.get("properties", {}), schema, "", top_rows, queue)
    if top_rows:
        lines += [
            "| field | type | unit | range | default | meaning |",
            "|---|---|---|---|---|---|",
            *top_rows,
            "",
        ]
    while queue:
        path, node = queue.pop(0)
        rows: list[str] = []
        sub: list[tuple[str, dict]] = []
        _section_rows(node.get("properties", {}), schema, "", rows, sub)
        queue[0:0] = [(f"{path}.{p}", n) for p, n in sub]
        required = set(node.get("required", []))
        lines += [f"### `[{path}]`", ""]
        if node.get("description"):
            lines += [_md_escape(node["description"]), ""]
        if required:
            lines += ["Required fields: " + ", ".join(f"`{r}`" for r in sorted(required)) + ".", ""]
        if rows:
            lines += [
                "| field | type | unit | range | default | meaning |",
                "|---|---|---|---|---|---|",
                *rows,
                "",
            ]
    return lines


def scenario_reference() -> dict[str, str]:
    import tomllib

    from formation_ftc.config.loader import builtin_scenarios
    from formation_ftc.registry import PLUGIN_ERRORS, methods

    registered = methods()
    if PLUGIN_ERRORS:
        raise PluginError(
            "plug-ins failed to import (their reference pages would be missing): "
            + "; ".join(f"{m}: {tb.strip().splitlines()[-1]}" for m, tb in PLUGIN_ERRORS.items())
        )
    by_method: dict[str, list[tuple[str, str]]] = {}
    for name, text in builtin_scenarios().items():
        meta = tomllib.loads(text)["scenario"]
        by_method.setdefault(meta.get("method", "composed"), []).append(
            (name, meta.get("description", ""))
        )
    pages = {}
    index = [
        "# Scenario file reference",
        "",
        "A scenario file is TOML data validated by the schema of the method named in `[scenario].method`. "
        "The pages below are generated from those schemas: every field, its type, unit, allowed range "
        "and default. Expressions (strings evaluated in `t` and `i`) follow the "
        "[expression language](../../expressions.md). `formation-ftc schema METHOD` prints the same "
        "schema as JSON Schema for editors ([how](../../howto/write-a-scenario.md#editor-completion)).",
        "",
        "| method | description | built-in scenarios |",
        "|---|---|---|",
    ]
    for name, method in sorted(registered.items()):
        schema = method.schema.model_json_schema()
        scenarios = by_method.get(name, [])
        index.append(
            f"| [`{name}`]({name}.md) | {_md_escape(method.description)} | "
            + ", ".join(f"`{s}`" for s, _ in scenarios)
            + " |"
        )
        lines = [
            f"# Method `{name}`",
            "",
            _md_escape(method.description),
            "",
            f'`[scenario] method = "{name}"`. JSON Schema: `formation-ftc schema {name}`.',
            "",
        ]
        if scenarios:
            lines += ["Built-in scenarios (`formation-ftc show NAME` prints one resolved):", ""]
            lines += [f"* `{s}` -- {_md_escape(d)}" for s, d in scenarios] + [""]
        lines += ["## Fields", ""] + schema_tables(schema)
        pages[f"reference/scenarios/{name}.md"] = "\n".join(lines)
    pages["reference/scenarios/index.md"] = "\n".join(index)
    return pages


def campaign_reference() -> str:
    from formation_ftc.campaign import spec as campaign_spec

    schema = campaign_spec.CampaignSpec.model_json_schema()
    doc = (campaign_spec.__doc__ or "").split("\n\n", 1)
    example = doc[1] if len(doc) > 1 else ""
    lines = [
        "# Campaign file reference",
        "",
        "A campaign file is TOML: a base scenario, fixed overrides, sampled or swept fields and optional "
        "traces. Generated from the campaign schema; the samplers are described after the tables.",
        "",
    ]
    lines += ["## Fields", ""] + schema_tables(schema)
    body = example.replace("A campaign file looks like::", "## Example\n\n```toml").replace(
        "\n\nSamplers:", "\n```\n\n## Samplers\n\nSamplers:"
    )
    body = "\n".join(ln[4:] if ln.startswith("    ") else ln for ln in body.splitlines())
    body = body.replace("``", "`")
    lines += [
        body,
        "",
        "## Sampling designs",
        "",
        '`[campaign] sampling` chooses how the random (non-grid) fields are drawn: `"random"` '
        '(independent pseudo-random draws, the default), `"sobol"` (scrambled Sobol\' points) or '
        '`"lhs"` (Latin hypercube). With `sobol` a run\'s values depend only on the campaign seed, '
        "its replicate number and the list of random fields; with `lhs` also on the number of runs. "
        "See [sweep a gain](../howto/sweep-a-gain.md).",
        "",
    ]
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------ papers
def papers_page() -> str:
    import tomllib

    from formation_ftc.config.loader import builtin_scenarios
    from formation_ftc.registry import reproductions

    scen: dict[str, list[str]] = {}
    for name, text in builtin_scenarios().items():
        scen.setdefault(tomllib.loads(text)["scenario"].get("method", "composed"), []).append(name)
    lines = [
        "# The papers",
        "",
        "Each paper's method is a reusable part (a registered method with its scenario schema) and its "
        "simulation study is one command: `formation-ftc reproduce PAPER --out DIR` writes the figures, "
        "a table of published versus reproduced values with the criterion and verdict of each row, the "
        "condition checks and `summary.json`; `formation-ftc reproduce all` writes one HTML page for all "
        "of them. The published-versus-ours table is computed by that command (it runs the full study), "
        "so it is not copied here.",
        "",
        "Where a paper is ambiguous or inconsistent, the implementation makes a documented choice; the "
        "identifiers below are the ones the condition checks and reports cite, each explained in "
        "[errata](errata.md); values the report compares with that no paper prints are in "
        "[reference values](references.md).",
        "",
    ]
    for paper, rep in reproductions().items():
        lines += [
            f"## `{paper}` -- {_md_escape(rep.title)}",
            "",
            f"*{_md_escape(rep.citation)}*",
            "",
            f"**What the reproduction runs:** {_md_escape(rep.description)}",
            "",
            f"Command: `formation-ftc reproduce {paper} --out out/{paper}`.",
            "",
        ]
        names = scen.get(paper, [])
        if names:
            lines += [
                "Scenarios: "
                + ", ".join(f"`{n}`" for n in names)
                + f" ([fields](reference/scenarios/{paper}.md)).",
                "",
            ]
        if rep.errata:
            lines += ["| id | choice made where the paper is ambiguous or wrong |", "|---|---|"]
            lines += [f"| `{eid}` | {_md_escape(text)} |" for eid, text in rep.errata] + [""]
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------- examples
def _sources_digest() -> str:
    h = hashlib.sha256()
    for p in sorted((ROOT / "src" / "formation_ftc").rglob("*")):
        if p.suffix in (".py", ".toml") and p.is_file():
            h.update(p.relative_to(ROOT).as_posix().encode())
            h.update(p.read_bytes())
    return h.hexdigest()


def _run_example(path: Path, digest: str) -> dict:
    key = hashlib.sha256(
        (path.read_text() + (EXAMPLES / "_common.py").read_text() + digest).encode()
    ).hexdigest()[:16]
    out = CACHE / f"{path.stem}-{key}"
    result = out / "result.json"
    if result.is_file():
        return json.loads(result.read_text())
    out.mkdir(parents=True, exist_ok=True)
    env = {
        **os.environ,
        "FORMATION_FTC_EXAMPLES_QUICK": "1",
        "MPLBACKEND": "Agg",
        "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]).rstrip(
            os.pathsep
        ),
    }
    proc = subprocess.run(
        [sys.executable, str(Path(__file__).with_name("run_example.py")), str(path), str(out)],
        env=env,
        capture_output=True,
        text=True,
        cwd=str(ROOT),
    )
    if proc.returncode != 0:
        raise PluginError(
            f"example {path.name} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-6000:]}"
        )
    return json.loads(result.read_text())


def _example_page(path: Path, run: dict | None, files: Files, config) -> str:
    lines: list[str] = []
    if run is None:
        import jupytext

        cells = [
            {"type": c.cell_type, "source": c.source, "stdout": "", "figures": []}
            for c in jupytext.read(path).cells
        ]
    else:
        cells = run["cells"]
    for cell in cells:
        if cell["type"] == "markdown":
            lines += [cell["source"], ""]
        elif cell["source"].strip():
            lines += ["```python", cell["source"].rstrip(), "```", ""]
            if cell.get("stdout", "").strip():
                lines += ["```text", cell["stdout"].rstrip(), "```", ""]
            for fig in cell.get("figures", []):
                png = Path(run["dir"]) / fig
                _gen(files, config, f"examples/img/{fig}", png.read_bytes())
                lines += [f"![figure](img/{fig})", ""]
    note = (
        f"*Executed for this page with `--quick` (reduced size) in {run['wall_s']:.1f} s.* "
        if run
        else "*Not executed in this build (FORMATION_FTC_DOCS_EXAMPLES=0).* "
    )
    lines += [
        "---",
        "",
        note + f"Source: `examples/{path.name}`; run it with `python examples/{path.name}` "
        "(full size) or add `--quick`.",
        "",
    ]
    return "\n".join(lines)


def examples_pages(files: Files, config) -> None:
    paths = sorted(EXAMPLES.glob("[0-9][0-9]_*.py"))
    execute = os.environ.get("FORMATION_FTC_DOCS_EXAMPLES", "1") not in ("0", "")
    runs: dict[Path, dict | None] = {p: None for p in paths}
    if execute:
        digest = _sources_digest()
        jobs = max(1, int(os.environ.get("FORMATION_FTC_DOCS_JOBS", "2")))
        with concurrent.futures.ThreadPoolExecutor(jobs) as pool:
            futures = {pool.submit(_run_example, p, digest): p for p in paths}
            for fut in concurrent.futures.as_completed(futures):
                runs[futures[fut]] = fut.result()
                log.info("example %s: %.1f s", futures[fut].name, runs[futures[fut]]["wall_s"])
    index = [
        "# Examples",
        "",
        "Each example is a script under `examples/` in jupytext percent format: run it with "
        "`python examples/NAME.py` (add `--quick` for a reduced size), or open it as a notebook with "
        "`jupytext --to notebook`. The pages below were produced by running them at reduced size "
        "during the documentation build.",
        "",
    ]
    for p in paths:
        page = _example_page(p, runs[p], files, config)
        title = next((ln[2:] for ln in page.splitlines() if ln.startswith("# ")), p.stem)
        index.append(f"* [{title}]({p.stem}.md) -- `examples/{p.name}`")
        _gen(files, config, f"examples/{p.stem}.md", page)
    _gen(files, config, "examples/index.md", "\n".join(index) + "\n")


# --------------------------------------------------------------------------------------------- hook
def _method_names() -> list[str]:
    sys.path.insert(0, str(ROOT / "src"))
    from formation_ftc.registry import methods

    return sorted(methods())


def on_config(config):
    """Fill the "Scenario files" section of the nav with one page per registered method (plug-ins
    included), after the section's own first entry (the index page)."""

    def fill(items):
        for item in items or []:
            if isinstance(item, dict):
                for title, value in item.items():
                    if title == "Scenario files" and isinstance(value, list) and value:
                        item[title] = [value[0]] + [
                            {n: f"reference/scenarios/{n}.md"} for n in _method_names()
                        ]
                    elif isinstance(value, list):
                        fill(value)

    fill(config["nav"])
    return config


def on_files(files: Files, config) -> Files:
    sys.path.insert(0, str(ROOT / "src"))
    _gen(files, config, "reference/cli.md", cli_reference())
    for path, text in scenario_reference().items():
        _gen(files, config, path, text)
    _gen(files, config, "reference/campaign-file.md", campaign_reference())
    _gen(files, config, "papers.md", papers_page())
    examples_pages(files, config)
    return files
