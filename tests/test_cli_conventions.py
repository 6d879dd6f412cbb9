"""Command-line conventions: fast start (no heavy imports), plain-text help with examples and exit
codes on every command, --version from the package metadata, ``python -m``, ``schema``, "did you
mean", -q/-v, output that is not truncated when piped."""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from importlib import metadata

import pytest

from formation_ftc import cli
from formation_ftc.suggest import close_matches, schema_paths, unknown_fields


def _all_parsers(parser: argparse.ArgumentParser, key: str = ""):
    yield key, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _all_parsers(sub, f"{key} {name}".strip())


def test_parser_imports_no_heavy_module():
    code = (
        "import sys; from formation_ftc.cli import build_parser; build_parser(None); build_parser('list');"
        "print(sorted(m for m in ('jax._src', 'scipy', 'pandas', 'pyarrow', 'xarray', 'matplotlib') "
        "if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", out.stdout


def test_version_from_metadata_and_python_m():
    out = subprocess.run(
        [sys.executable, "-m", "formation_ftc", "--version"],
        capture_output=True,
        text=True,
        check=True,
    )
    assert out.stdout.strip() == f"formation-ftc {metadata.version('formation-ftc')}"


def test_every_command_has_examples_exit_codes_and_verbosity():
    parsers = dict(_all_parsers(cli.build_parser()))
    assert {
        "list",
        "show",
        "check",
        "schema",
        "run",
        "reproduce",
        "campaign",
        "campaign run",
    } <= set(parsers)
    for key, p in parsers.items():
        text = p.format_help()
        assert "exit status:" in text and "  2  bad input" in text, key
        assert "--quiet" in text and "--verbose" in text, key
        assert "``" not in text and ":mod:" not in text, key  # plain text, no reStructuredText
        if key in cli.HELP:
            assert "examples:" in text and cli.HELP[key][1][0] in text, key
            # every example parses with this parser (help examples that do not work are worse than none)
            for example in cli.HELP[key][1]:
                argv = example.split()[1:]
                if "COMMAND" in argv or "|" in argv or ">" in argv:
                    argv = argv[
                        : next(i for i, a in enumerate(argv + ["|"]) if a in ("COMMAND", "|", ">"))
                    ]
                if argv:
                    cli.build_parser().parse_args(argv)


def test_verbosity_flags_anywhere():
    p = cli.build_parser()
    assert p.parse_args(["-q", "list"]).verbosity == -1
    assert p.parse_args(["list", "-v"]).verbosity == 1
    assert p.parse_args(["campaign", "list", "--quiet"]).verbosity == -1
    assert p.parse_args(["list"]).verbosity == 0
    with pytest.raises(SystemExit):
        p.parse_args(["list", "-q", "-v"])


def test_list_matches_the_scenario_loader(capsys):
    from formation_ftc.api import list_scenarios

    assert cli.main(["list"]) == 0
    lines = [
        ln for ln in capsys.readouterr().out.splitlines() if ln.strip() and not ln.endswith(":")
    ]
    expected = (
        list_scenarios()
    )  # (section headings such as "Cross-paper compositions ...:" skipped)
    assert sorted(ln.split()[0] for ln in lines) == sorted(expected)
    assert all(ln.rstrip().endswith(expected[ln.split()[0]]) for ln in lines)


def test_unknown_scenario_suggests_close_names(capsys):
    assert cli.main(["show", "li2020-thm"]) == 2
    err = capsys.readouterr().err
    assert "did you mean 'li2020-thm1'" in err


def test_unknown_field_suggests_the_field(capsys):
    assert cli.main(["show", "cw-pd-fault", "--set", "controler.kp=3"]) == 2
    assert "did you mean 'controller'" in capsys.readouterr().err
    assert cli.main(["show", "cw-pd-fault", "--set", "controller.kpp=3"]) == 2
    assert "unknown field controller.kpp (did you mean 'kp'?)" in capsys.readouterr().err


def test_schema_command_accepts_every_builtin_scenario(capsys):
    import tomllib

    from formation_ftc.config.loader import builtin_scenarios

    seen = {}
    for name, text in builtin_scenarios().items():
        raw = tomllib.loads(text)
        method = raw["scenario"].get("method", "composed")  # optional: composed by default
        if method not in seen:
            assert cli.main(["schema", method]) == 0
            seen[method] = json.loads(capsys.readouterr().out)
        schema = seen[method]
        assert schema["$schema"].startswith("https://json-schema.org/")
        assert unknown_fields(raw, schema) == [], name
        # every field the file sets is a path of the schema (lists of tables excepted)
        paths = set(schema_paths(schema))
        assert {f"{section}" for section in raw} <= paths, name
    # a misspelt field is found where it is and the right name is suggested
    raw = tomllib.loads(builtin_scenarios()["cw-pd-fault"])
    raw["simulation"]["horizn"] = raw["simulation"].pop("horizon")
    bad = unknown_fields(raw, seen["composed"])
    assert [(u.path, u.suggestions[0]) for u in bad] == [("simulation.horizn", "horizon")]
    assert cli.main(["schema", "composd"]) == 2
    assert "did you mean 'composed'" in capsys.readouterr().err


def test_close_matches_prefix_and_nothing():
    assert close_matches("li2020", ["li2020-thm1", "gui2022-ilo"])[0] == "li2020-thm1"
    assert close_matches("zzzz", ["li2020-thm1", "gui2022-ilo"]) == []


def test_check_output_not_truncated_when_piped(capsys):
    from formation_ftc.api import check, load_scenario

    code = cli.main(["check", "li2020-thm1"])
    out = capsys.readouterr().out
    conds = check(load_scenario("li2020-thm1"))
    assert code == (1 if any(c.required and c.holds is False for c in conds) else 0)
    lines = out.splitlines()
    assert max(len(ln) for ln in lines) > 80 or all(len(ln) <= 80 for ln in lines)
    for c in conds:  # every value printed whole on its condition's line
        assert any(ln.startswith(c.name) and str(c.value) in ln for ln in lines), c.name


def test_show_annotates_units_without_changing_values(capsys):
    import tomllib

    assert cli.main(["show", "cw-pd-fault", "--set", "controller.kp=3"]) == 0
    annotated = capsys.readouterr().out
    assert cli.main(["show", "cw-pd-fault", "--set", "controller.kp=3", "--no-comments"]) == 0
    bare = capsys.readouterr().out
    assert "#" not in bare and tomllib.loads(annotated) == tomllib.loads(bare)
    kp_line = next(ln for ln in annotated.splitlines() if ln.startswith("kp ="))
    assert kp_line.startswith("kp = 3 ") and "[N/m]" in kp_line  # a composed table keeps its values


def test_composed_schema_validates_every_builtin_scenario_and_rejects_bad_tables(capsys):
    """`schema composed` gives each slot a oneOf over its component types: every built-in scenario
    validates against it (an independent JSON Schema validator), a wrong value or an unknown field in
    a slot table does not."""
    jsonschema = pytest.importorskip("jsonschema")
    import tomllib

    from formation_ftc.config.loader import builtin_scenarios

    assert cli.main(["schema", "composed"]) == 0
    validator = jsonschema.Draft202012Validator(json.loads(capsys.readouterr().out))
    for name, text in builtin_scenarios().items():
        assert not list(validator.iter_errors(tomllib.loads(text))), name
    raw = tomllib.loads(builtin_scenarios()["cw-pd-fault"])
    raw["controller"]["kp"] = -1.0  # the pd section: kp >= 0
    assert list(validator.iter_errors(raw))
    raw = tomllib.loads(builtin_scenarios()["cw-pd-fault"])
    raw["controller"]["kpp"] = 1.0  # no such field of any controller type
    assert list(validator.iter_errors(raw))
