"""``--json`` of the command line (typed values, units in separate keys, errors as JSON documents), the
exit status of a stdout that cannot be written, the shell completion script and the examples' figures."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from formation_ftc import cli
from formation_ftc.cli import main
from formation_ftc.condition_json import condition_json

ROOT = Path(__file__).resolve().parents[1]
SHORT = ["--set", "simulation.horizon=10"]  # cw-free-drift: 10 steps of 1 s


def _doc(capsys) -> dict:
    return json.loads(capsys.readouterr().out)


def _is_number(v) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool)


# ----------------------------------------------------------------------------------- typed documents
def test_list_json(capsys):
    assert main(["list", "--json"]) == 0
    rows = _doc(capsys)["scenarios"]
    from formation_ftc.api import list_scenarios

    assert sorted(r["name"] for r in rows) == sorted(list_scenarios())
    for r in rows:
        assert set(r) == {"name", "method", "paper", "description", "composed"}
        assert isinstance(r["composed"], bool) and r["composed"] == (r["method"] == "composed")
        assert isinstance(r["description"], str) and r["description"]
        assert r["paper"] is None or isinstance(r["paper"], str)
    papers = {r["paper"] for r in rows}
    assert papers >= {"li2020", "yang2013", "gui2022", "mehrabian", "azizi2009", None}


def test_show_json_is_the_toml_with_units(capsys):
    args = ["show", "cw-pd-fault", "--set", "controller.kp=3"]
    assert main([*args, "--no-comments"]) == 0
    toml = tomllib.loads(capsys.readouterr().out)
    assert main([*args, "--json"]) == 0
    doc = _doc(capsys)
    assert doc["scenario"] == toml  # the same content, the same types
    assert doc["scenario"]["controller"]["kp"] == 3.0 and isinstance(
        doc["scenario"]["simulation"]["seed"], int
    )
    units = doc["units"]
    assert units["controller.kp"] == "N/m" and units["simulation.horizon"] == "s"
    assert units["plant.mass"] == "kg" and units["actuator.effectiveness"] == "1"  # "[-]"
    assert (
        "controller.desired_position" not in units
    )  # its description states [s] and [m]: no guess
    assert all(isinstance(u, str) and u for u in units.values())


def test_description_units():
    f = cli._description_unit
    assert f("Position gain [N/m].") == "N/m" and f("Count [-].") == "1"
    assert (
        f("Biased attitude per channel [rad], expressions in t [s].") is None
    )  # two different units
    assert f("Draw every Euler angle from U[range].") is None and f("Gain [12] [m/s^2].") == "m/s^2"
    assert f("No unit.") is None and f("Inertia [kg m^2], spread [-u, u].") == "kg m^2"


def test_check_json_typed(capsys):
    assert main(["check", "cw-pd-fault", "--json"]) == 0
    doc = _doc(capsys)
    assert doc["scenario"] == "cw-pd-fault" and doc["method"] == "composed"
    assert doc["all_required_hold"] is True and doc["exit_code"] == 0
    assert doc["required_failed"] == 0 and doc["required_unproven"] == 0
    first = next(c for c in doc["conditions"] if c["name"].startswith("closed-loop stable"))
    assert first["value_text"].startswith("max Re(eig) = ")
    assert _is_number(first["value"]) and first["value"] < 0 and first["units"] == "1/s"
    assert first["quantities"] == [{"name": "max Re(eig)", "value": first["value"], "units": "1/s"}]
    assert first["bound"]["relation"] == "<" and _is_number(first["bound"]["value"])
    for c in doc["conditions"]:
        assert c["holds"] in (True, False, None) and isinstance(c["required"], bool)
        assert isinstance(c["unproven"], bool) and isinstance(c["value_text"], str)
        assert c["value"] is None or isinstance(c["value"], int | float | list | bool)
    # a failing required condition: exit status 1, the document all the same
    assert (
        main(
            [
                "check",
                "cw-pd-fault",
                "--set",
                "controller.kd=0",
                "--set",
                "controller.kp=0",
                "--json",
            ]
        )
        == 1
    )
    doc = _doc(capsys)
    assert (
        doc["exit_code"] == 1 and doc["all_required_hold"] is False and doc["required_failed"] >= 1
    )


@pytest.mark.parametrize(
    "statement,value,units,names",
    [
        ("max Re(eig) = -0.09989 1/s", -0.09989, "1/s", ["max Re(eig)"]),
        ("max eig = -1e-08 (lambda = 1e-08)", -1e-08, None, ["max eig", "lambda"]),
        (
            "e_s = 0.03 m, T = 1.07e-05 m",
            None,
            None,
            ["e_s", "T"],
        ),  # two side by side: no single value
        ("alpha = [1.0, 1.0, 1.0, 1.0]", [1.0] * 4, None, ["alpha"]),
        ("0.01 1/s (K1 = 0.005, K2 = 0.01)", 0.01, "1/s", [None, "K1", "K2"]),
        (
            "1/2[(1 - alpha) K - 1/gamma^2] = 0.0111111 N m s",
            0.0111111,
            "N m s",
            ["1/2[(1 - alpha) K - 1/gamma^2]"],
        ),
        (
            "dt max|lambda| = 0.02, max |R(lambda dt)| = 0.9901 (at lambda = -0.0999+0.00215j 1/s)",
            None,
            None,
            ["dt max|lambda|", "max |R(lambda dt)|"],
        ),  # a complex number is not a quantity
        (
            "max dT/dt = 0.4405 (T12 at t = 1.55 s); verified <= 0.555403",
            0.4405,
            None,
            ["max dT/dt", "T12 at t"],
        ),
        ("True", True, None, [None]),
        ("NOT balanced: row sums [0.5, 0.6], column sums [1.2, 0.5]", None, None, []),
    ],
)
def test_condition_statement_quantities(statement, value, units, names):
    from formation_ftc.registry import Condition

    c = condition_json(Condition("c", "ref", statement, "< 0", None, basis="exact"))
    assert c["value"] == value and c["units"] == units and c["value_text"] == statement
    assert [q["name"] for q in c["quantities"]] == names


def test_requirement_bound():
    from formation_ftc.registry import Condition

    def bound(req):
        return condition_json(Condition("c", "ref", "0", req, None, basis="exact"))["bound"]

    assert bound("<= 5e-5 (K printed to 4 decimals)") == {
        "relation": "<=",
        "value": 5e-5,
        "units": None,
    }
    assert bound("> 0") == {"relation": ">", "value": 0.0, "units": None}
    assert bound("< 1 - 6.6e-09 (rounding margin)") is None and bound(">= eta = 0.01") is None


def test_run_json_typed_and_diverged(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", "cw-free-drift", *SHORT, "--out", str(out), "--json"]) == 0
    doc = _doc(capsys)
    assert doc["scenario"] == "cw-free-drift" and doc["exit_code"] == 0 and doc["diverged"] is None
    assert doc["n_steps"] == 10 and doc["units"] == {"wall_time": "s", "simulation_time": "s"}
    # the command's wall time includes the simulation's
    assert _is_number(doc["simulation_time"]) and doc["wall_time"] > doc["simulation_time"] > 0
    saved = json.loads((out / "metrics.json").read_text())
    for name, m in doc["metrics"].items():
        assert set(m) == {"value", "units"} and _is_number(m["value"]) and m["value"] == saved[name]
        assert m["units"] == saved["units"][name]
    assert doc["metrics"]["delta_v_total"]["units"] == "m s-1"
    outputs = doc["outputs"]
    assert (
        outputs["dir"] == str(out)
        and Path(outputs["result"]).is_file()
        and Path(outputs["index"]).is_file()
    )
    assert outputs["figures"] == [] and not list(out.glob("*.png"))  # figures: --figures, `plot`
    # a run that leaves its admissible set: exit status 1, the document with the diagnostic
    out2 = tmp_path / "div"
    assert (
        main(
            [
                "run",
                "cw-free-drift",
                *SHORT,
                "--set",
                "simulation.max_position=50",
                "--out",
                str(out2),
                "--json",
            ]
        )
        == 1
    )
    doc = _doc(capsys)
    d = doc["diverged"]
    assert doc["exit_code"] == 1 and Path(doc["outputs"]["result"]).is_file()
    assert _is_number(d["time"]) and isinstance(d["step"], int) and d["units"] == {"time": "s"}
    assert d["spacecraft"] in (1, 2) and isinstance(d["index"], list) and "diverged" in d["message"]


def test_campaign_and_league_list_json(capsys):
    from formation_ftc.campaign import builtin_campaigns
    from formation_ftc.league.definition import builtin_leagues

    assert main(["campaign", "list", "--json"]) == 0
    rows = _doc(capsys)["campaigns"]
    assert [r["name"] for r in rows] == sorted(builtin_campaigns())
    assert all(isinstance(r["base"], list) and isinstance(r["runs"], int) for r in rows)
    assert main(["league", "list", "--json"]) == 0
    rows = _doc(capsys)["leagues"]
    assert sorted(r["name"] for r in rows) == sorted(builtin_leagues())
    for r in rows:
        assert (
            isinstance(r["seeds"], int)
            and _is_number(r["horizon"])
            and r["units"] == {"horizon": "s"}
        )
        assert _is_number(r["requirement"]["max"]) and isinstance(r["requirement"]["units"], str)
        assert r["methods"] and all(isinstance(m, str) for m in r["methods"])


# ---------------------------------------------------------------------------------------- errors
def test_json_error_documents(capsys, monkeypatch, tmp_path):
    assert main(["show", "no-such-scenario", "--json"]) == 2
    captured = capsys.readouterr()
    assert captured.err.startswith("error: unknown scenario")  # stderr as without --json
    assert json.loads(captured.out) == {
        "error": captured.err.strip().removeprefix("error: "),
        "exit_code": 2,
    }
    assert main(["show", "no-such-scenario"]) == 2
    assert capsys.readouterr().out == ""  # no document without --json
    # a usage error of the argument parser (status 2, SystemExit as before)
    with pytest.raises(SystemExit) as exc:
        main(["run", "cw-free-drift", "--json"])
    assert exc.value.code == 2
    doc = json.loads(capsys.readouterr().out)
    assert doc == {
        "error": "formation-ftc run: the following arguments are required: --out",
        "exit_code": 2,
    }
    # an unexpected error (status 3)
    monkeypatch.setenv("FORMATION_FTC_CRASH_DIR", str(tmp_path))
    monkeypatch.setattr(cli, "_cmd_list", lambda args: {}["boom"])
    assert main(["list", "--json"]) == 3
    doc = _doc(capsys)
    assert doc["exit_code"] == 3 and doc["error"].startswith("internal error: KeyError")


def test_only_a_failing_stdout_is_exit_status_1(capsys, monkeypatch, tmp_path):
    """An OSError (even a broken pipe) of something else than stdout is unexpected (3), not 1 or 0."""
    from formation_ftc.exitcodes import run_guarded

    monkeypatch.setenv("FORMATION_FTC_CRASH_DIR", str(tmp_path))

    class Args:
        json = False

    def disk_full(args):
        raise OSError(28, "No space left on device")

    def worker_pipe(args):
        raise BrokenPipeError(32, "Broken pipe")

    assert run_guarded(disk_full, Args()) == 3
    assert run_guarded(worker_pipe, Args()) == 3
    assert "internal error: BrokenPipeError" in capsys.readouterr().err


def _run_cli(*args, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "formation_ftc.cli", *args],
        capture_output=False,
        timeout=600,
        **kwargs,
    )


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
def test_full_or_closed_stdout_exits_1_with_one_line():
    with open("/dev/full", "w") as full:
        proc = _run_cli("show", "li2020-thm1", stdout=full, stderr=subprocess.PIPE, text=True)
    assert proc.returncode == 1
    assert proc.stderr.strip().splitlines() == [
        "cannot write to standard output: No space left on device"
    ]
    # a closed descriptor (`>&-`): Python's sys.stdout is None
    proc = subprocess.run(
        ["sh", "-c", 'exec "$@" >&-', "sh", sys.executable, "-m", "formation_ftc.cli", "list"],
        stderr=subprocess.PIPE,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 1
    assert proc.stderr.strip() == "cannot write to standard output: standard output is closed"


# ------------------------------------------------------------------------------------ completion
def test_completion_scripts_without_jax():
    code = (
        "import sys, io, contextlib\n"
        "from formation_ftc.cli import main\n"
        "for shell in ('bash', 'zsh', 'tcsh'):\n"
        "    buf = io.StringIO()\n"
        "    with contextlib.redirect_stdout(buf):\n"
        "        assert main(['completion', shell]) == 0\n"
        "    open(sys.argv[1] + '.' + shell, 'w').write(buf.getvalue())\n"
        "print(sorted(m for m in ('jax._src', 'scipy', 'pandas', 'pydantic', 'numpy') if m in sys.modules))\n"
    )
    tmp = Path(os.environ.get("TMPDIR", "/tmp")) / f"formation-ftc-completion-{os.getpid()}"
    try:
        out = subprocess.run(
            [sys.executable, "-c", code, str(tmp)],
            capture_output=True,
            text=True,
            check=True,
            timeout=300,
        )
        assert out.stdout.strip() == "[]", out.stdout  # no JAX (nor numpy): answers at once
        bash = Path(f"{tmp}.bash").read_text()
        zsh = Path(f"{tmp}.zsh").read_text()
        tcsh = Path(f"{tmp}.tcsh").read_text()
    finally:
        for shell in ("bash", "zsh", "tcsh"):
            Path(f"{tmp}.{shell}").unlink(missing_ok=True)
    assert bash.rstrip().endswith("formation-ftc") and zsh.startswith("#compdef formation-ftc")
    for script in (bash, zsh, tcsh):
        for word in (
            "show",
            "check",
            "run",
            "reproduce",
            "campaign",
            "league",
            "completion",
            "--set",
            "--json",
            "--max-run-steps",
            "cw-pd-fault",
            "li2020-thm1",
        ):
            assert (word if script is not tcsh else word.lstrip("-")) in script, (
                word
            )  # tcsh: "c/--/(set ...)"
    assert (
        "cw-pd-gains" in bash and "translational" in bash and "gui2022" in bash
    )  # campaign, league, paper
    if shutil.which("bash"):
        subprocess.run(["bash", "-n"], input=bash, text=True, check=True)


@pytest.mark.skipif(not shutil.which("bash"), reason="needs bash")
def test_bash_completion_completes_commands_options_and_scenarios(tmp_path, capsys):
    assert main(["completion", "bash"]) == 0
    script = tmp_path / "formation-ftc.bash"
    script.write_text(capsys.readouterr().out)
    probe = (
        f"source {script}\n"
        't() { COMP_WORDS=("$@"); COMP_CWORD=$((${#COMP_WORDS[@]}-1)); COMPREPLY=(); '
        '_shtab_formation_ftc; echo "${COMPREPLY[*]}"; }\n'
        "t formation-ftc sh\nt formation-ftc show li2020-th\nt formation-ftc run x --max-\n"
        "t formation-ftc campaign run cw-pd\n"
    )
    out = subprocess.run(
        ["bash", "-c", probe], capture_output=True, text=True, check=True, cwd=tmp_path
    )
    lines = out.stdout.splitlines()
    assert lines[0] == "show"
    assert set(lines[1].split()) == {"li2020-thm1", "li2020-thm2-balanced", "li2020-thm2-delays"}
    assert set(lines[2].split()) == {"--max-memory", "--max-run-steps"}
    assert lines[3] == "cw-pd-gains"


def test_completion_matches_reproduce():
    """The completion script builds `reproduce`'s arguments without its module (which imports JAX): the
    same script as from the real parser."""
    import shtab

    full = cli.build_parser("")
    cli._add_completion_hints(full)
    assert shtab.complete(full, shell="bash") == shtab.complete(
        cli.completion_parser(), shell="bash"
    )


# -------------------------------------------------------------------------------------- examples
def test_example_run_as_a_script_saves_its_figure(tmp_path):
    """Run directly, an example writes its figures to figures/ next to it and prints where (the cheapest
    example with a figure, copied with _common.py so that nothing is written into the source tree)."""
    for name in ("_common.py", "04_lmi_observer.py"):
        shutil.copy(ROOT / "examples" / name, tmp_path / name)
    env = {**os.environ, "MPLBACKEND": "Agg"}
    env.pop("FORMATION_FTC_EXAMPLES_SAVE", None)
    proc = subprocess.run(
        [sys.executable, str(tmp_path / "04_lmi_observer.py"), "--quick"],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
        cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    png = tmp_path / "figures" / "04_lmi_observer_poles.png"
    assert png.is_file() and png.read_bytes().startswith(b"\x89PNG")
    assert f"figure saved to {png}" in proc.stdout


def test_example_figures_are_not_saved_by_the_docs_build(tmp_path, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    monkeypatch.syspath_prepend(str(ROOT / "examples"))
    import _common

    fig = plt.figure()
    namespace = {
        "__file__": str(tmp_path / "99_probe.py"),
        "save_figure": _common.save_figure,
        "fig": fig,
    }
    monkeypatch.setenv("FORMATION_FTC_EXAMPLES_SAVE", "0")  # what docs/hooks/run_example.py sets
    exec("result = save_figure(fig, 'x')", namespace)  # noqa: S102 - an example's cell
    assert namespace["result"] is None and not (tmp_path / "figures").exists()
    monkeypatch.delenv("FORMATION_FTC_EXAMPLES_SAVE")
    exec("result = save_figure(fig, 'x')", namespace)  # noqa: S102
    assert (
        namespace["result"] == tmp_path / "figures" / "99_probe_x.png"
        and namespace["result"].is_file()
    )
    plt.close(fig)
