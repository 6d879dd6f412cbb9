"""Hostile and careless input on the command line: every case ends with exit status 2 and one message
naming what to fix (never a traceback), unexpected errors exit 3 with a saved traceback, a closed
pipe ends quietly, and ``run`` never leaves a directory mixing two runs."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import xarray as xr

from formation_ftc.cli import main

SCN = "cw-pd-fault"
SHORT = ["--set", "simulation.horizon=20"]  # 200 steps: the program of the other short runs


def _expr(text: str) -> list[str]:
    return ["--set", f"actuator.bias.0={text}"]


DEEP_TOML = "a = " + "[" * 900 + "]" * 900 + "\n"

#: (id, scenario arguments, fragment of the message) -- each must exit 2 before anything runs
HOSTILE = [
    ("operator-chain", _expr("+".join(["1"] * 999)), "nested too deeply (more than 200 levels"),
    ("unary-chain", _expr("-" * 999 + "t"), "nested too deeply"),
    ("400-digit-literal-string", _expr('"1' + "0" * 400 + '"'), "outside the float64 range"),
    ("400-digit-literal-toml", _expr("1" + "0" * 400), "finite number"),
    ("div-zero", _expr("1/0"), "division by a constant zero"),
    ("mod-zero", _expr("1%0"), "modulo by a constant zero"),
    ("power-tower", _expr("9**9**9**9"), "not a finite float64 (overflow"),
    ("ten-to-400", _expr("10**400"), "not a finite float64 (overflow"),
    ("log-zero", _expr("2*log(0)"), "not a finite float64"),
    (
        "horizon-inf",
        ["--set", "simulation.horizon=inf"],
        "field simulation.horizon: Input should be a finite number",
    ),
    ("horizon-nan", ["--set", "simulation.horizon=nan"], "finite number"),
    ("seed-2**32", ["--set", f"simulation.seed={2**32}"], "field simulation.seed"),
    (
        "set-index-out-of-range",
        ["--set", "plant.mass.99=5"],
        "index 99 is out of range; the list has 4",
    ),
    ("set-through-a-number", ["--set", "plant.mass.0.x=1"], "plant.mass.0 is a number"),
    ("set-negative-index", ["--set", "plant.mass.-1=1"], "must be a non-negative integer"),
    (
        "bool-as-number",
        ["--set", "simulation.horizon=true"],
        "got a boolean (booleans are not numbers)",
    ),
    ("bool-in-list", ["--set", "plant.mass=[true, 1.0, 1.0, 1.0]"], "got a boolean"),
    (
        "trailing-toml",
        ["--set", "simulation.horizon=100\nsimulation.dt=2"],
        "a single TOML value on one line",
    ),
    ("broken-toml-value", ["--set", "plant.mass=[1,"], "invalid TOML value"),
    (
        "mass-inf",
        ["--set", "plant.mass.0=inf"],
        "plant.mass[0]: inf is refused: must be a finite number",
    ),
    ("gain-inf", ["--set", "controller.kp=inf"], "controller.kp: Input should be a finite number"),
    ("sma-inf", ["--set", "plant.semi_major_axis=inf"], "plant.semi_major_axis"),
    ("expr-number-inf", ["--set", "actuator.bias.0=inf"], "finite number"),
]


@pytest.mark.parametrize("args,fragment", [c[1:] for c in HOSTILE], ids=[c[0] for c in HOSTILE])
@pytest.mark.parametrize("command", ["check", "run"])
def test_hostile_scenario_input_exits_2(command, args, fragment, tmp_path, capsys):
    extra = ["--out", str(tmp_path / "o")] if command == "run" else []
    assert main([command, SCN, *args, *extra]) == 2
    err = capsys.readouterr().err
    assert fragment in err and "Traceback" not in err
    assert err.startswith("error: ")
    assert not (tmp_path / "o").exists()  # nothing written


@pytest.mark.parametrize(
    "args,fragment",
    [
        (
            ["--set", "simulation.horizon=1e308", "--set", "simulation.dt=1e-308"],
            "not a countable number of steps",
        ),
        (
            ["--set", "plant.semi_major_axis=1e300"],
            "plant: semi_major_axis = 1e+300 m: the mean motion sqrt(mu / a^3) [rad/s] is not a finite",
        ),
        (
            ["--set", "plant.mass.0=1e-320"],
            "the conditions cannot be evaluated for these values",
        ),
        (["--set", "plant.mass.\u0663=1"], "must be a non-negative integer"),
    ],
    ids=["steps-overflow", "sma-1e300", "subnormal-mass", "non-ascii-index"],
)
def test_extreme_values_in_check_exit_2(args, fragment, capsys):
    assert main(["check", SCN, *args]) == 2
    err = capsys.readouterr().err
    assert fragment in err and "Traceback" not in err


def test_deeply_nested_and_non_utf8_and_unreadable_files(tmp_path, capsys, monkeypatch):
    deep = tmp_path / "deep.toml"
    deep.write_text(DEEP_TOML)
    assert main(["check", str(deep)]) == 2
    assert f"{deep}: TOML nested more than 32 levels" in capsys.readouterr().err
    bad = tmp_path / "latin1.toml"
    bad.write_bytes("[scenario]\nname = 'caf\xe9'\n".encode("latin-1"))
    assert main(["check", str(bad)]) == 2
    assert f"scenario file {str(bad)!r} is not UTF-8 text" in capsys.readouterr().err
    locked = tmp_path / "locked.toml"
    locked.write_text("[scenario]\n")

    def deny(self):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(Path, "read_bytes", deny)
    assert main(["check", str(locked)]) == 2
    assert (
        f"scenario file {str(locked)!r} cannot be read (Permission denied)"
        in capsys.readouterr().err
    )
    monkeypatch.undo()
    a_dir = tmp_path / "dir.toml"
    a_dir.mkdir()
    assert main(["check", str(a_dir)]) == 2
    assert "is not a regular file" in capsys.readouterr().err


@pytest.mark.parametrize(
    "out,fragment",
    [
        ("", "--out: empty path"),
        ("/dev/null", "is not a directory"),
        ("FILE", "exists and is a file"),
        ("/sys/formation-ftc-test/x", "cannot write in /sys"),
        ("/proc/formation-ftc-test", "cannot write in /proc"),
    ],
    ids=["empty", "dev-null", "file", "read-only-sysfs", "procfs"],
)
def test_bad_out_paths_exit_2_before_running(out, fragment, tmp_path, capsys):
    if out == "FILE":
        out = str(tmp_path / "a-file")
        Path(out).write_text("keep me")
    assert main(["run", SCN, *SHORT, "--out", out]) == 2
    err = capsys.readouterr().err
    assert fragment in err and "Traceback" not in err
    if out.endswith("a-file"):
        assert Path(out).read_text() == "keep me"


def test_run_refuses_foreign_directory_without_force_and_replaces_its_own_result(tmp_path, capsys):
    foreign = tmp_path / "thesis"
    foreign.mkdir()
    (foreign / "chapter1.tex").write_text("precious")
    assert main(["run", SCN, *SHORT, "--out", str(foreign)]) == 2
    assert "is not the result of an earlier `formation-ftc run`" in capsys.readouterr().err
    assert (foreign / "chapter1.tex").read_text() == "precious"
    out = tmp_path / "run"
    assert main(["run", SCN, *SHORT, "--out", str(out)]) == 0
    assert (
        main(["run", SCN, "--set", "simulation.horizon=60", "--out", str(out)]) == 0
    )  # its own: replaced
    with xr.open_dataset(out / "result.nc", engine="h5netcdf") as ds:
        assert float(ds["time"][-1]) == pytest.approx(60.0)
    assert not [
        p for p in tmp_path.iterdir() if p.name.startswith(".")
    ]  # no staging directory left
    assert main(["run", SCN, *SHORT, "--out", str(foreign), "--force"]) == 0
    assert not (foreign / "chapter1.tex").exists() and (foreign / "result.nc").exists()


def test_failure_while_writing_leaves_the_previous_run_whole(tmp_path, capsys, monkeypatch):
    out = tmp_path / "run"
    assert main(["run", SCN, *SHORT, "--out", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    import formation_ftc.api as api

    real = api.save_result

    def fails_after_the_netcdf(ds, out_dir, metrics=None):
        real(ds, out_dir, metrics)
        (Path(out_dir) / "metrics.json").unlink()
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(api, "save_result", fails_after_the_netcdf)
    monkeypatch.setenv("FORMATION_FTC_CRASH_DIR", str(tmp_path / "crash"))
    assert main(["run", SCN, "--set", "simulation.horizon=60", "--out", str(out)]) == 3
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before  # the previous run, whole
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_save_result_never_pairs_a_new_result_with_old_metrics(tmp_path, monkeypatch):
    from formation_ftc.api import load_scenario, save_result, simulate

    ds = simulate(load_scenario(SCN, {"simulation.horizon": 20.0}))
    save_result(ds, tmp_path, {"a": 1.0})
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    ds2 = ds.copy()
    ds2.attrs["scenario_name"] = "second"
    import pathlib

    real_write = pathlib.Path.write_text

    def full_disk(self, *a, **k):
        if self.name.startswith(".metrics.json.tmp"):
            raise OSError(28, "No space left on device")
        return real_write(self, *a, **k)

    monkeypatch.setattr(pathlib.Path, "write_text", full_disk)
    with pytest.raises(OSError):
        save_result(ds2, tmp_path, {"a": 2.0})
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def test_resource_budgets_refuse_before_compiling(tmp_path, capsys, monkeypatch):
    assert main(["run", SCN, "--set", "simulation.horizon=1e12", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert (
        "integration steps per run" in err
        and "simulation.horizon" in err
        and "--max-run-steps" in err
    )
    args = [
        "run",
        SCN,
        "--set",
        "simulation.horizon=1e6",
        "--set",
        "simulation.record_every=1",
        "--out",
        str(tmp_path / "o"),
    ]
    assert main([*args, "--max-memory", "50MB"]) == 2
    err = capsys.readouterr().err
    assert "of memory for its records and state" in err and "simulation.record_every" in err
    monkeypatch.setenv("FORMATION_FTC_MAX_MEMORY", "50MB")
    assert main(args) == 2  # the environment variable sets the same budget
    assert "over the budget of 47.7 MiB" in capsys.readouterr().err
    assert main([*args[:-2], "--out", str(tmp_path / "o"), "--max-memory", "lots"]) == 2
    assert "--max-memory: expected a size" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_plots_subsample_thousands_of_spacecraft():
    import numpy as np

    from formation_ftc.runout import plot_view

    ds = xr.Dataset({"x": (("time", "spacecraft"), np.zeros((2, 10_000)))})
    view, note = plot_view(ds, 50)
    assert view.sizes["spacecraft"] == 50 and "50 of 10000 spacecraft" in note
    assert (
        int(view["spacecraft"].size) == 50
        and plot_view(ds.isel(spacecraft=slice(0, 7)), 50)[1] == ""
    )


def test_run_with_hundreds_of_spacecraft_plots_a_subset(tmp_path, capsys):
    import tomllib

    import tomli_w

    from formation_ftc.config.loader import builtin_scenarios

    raw = tomllib.loads(builtin_scenarios()[SCN])
    n = 300
    raw["plant"]["mass"] = [100.0] * n
    raw["controller"]["nominal_mass"] = [100.0] * n  # the law's stated masses, one per deputy too
    raw["plant"]["initial_position"] = [[float(k % 20), float(k // 20), 0.0] for k in range(n)]
    raw["simulation"]["horizon"] = 2.0
    path = tmp_path / "many.toml"
    path.write_text(tomli_w.dumps(raw))
    assert main(["run", str(path), "--out", str(tmp_path / "o"), "--figures"]) == 0
    assert "figures show 16 of 300 spacecraft" in capsys.readouterr().err
    with xr.open_dataset(tmp_path / "o" / "result.nc", engine="h5netcdf") as ds:
        assert ds.sizes["spacecraft"] == n  # the data keeps every spacecraft


def test_unexpected_error_exits_3_with_a_saved_traceback(tmp_path, capsys, monkeypatch):
    import formation_ftc.cli as cli

    def boom(args):
        raise RuntimeError("something inside broke")

    monkeypatch.setenv("FORMATION_FTC_CRASH_DIR", str(tmp_path))
    monkeypatch.setattr(cli, "_cmd_check", boom)
    assert main(["check", SCN]) == 3
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "RuntimeError: something inside broke" in err
    crash = next(tmp_path.glob("crash-*.txt"))
    assert (
        str(crash) in err
        and "Traceback" in crash.read_text()
        and "something inside broke" in crash.read_text()
    )
    monkeypatch.setattr(cli, "_cmd_check", lambda args: {}["missing-key"])
    assert main(["check", SCN]) == 3  # a KeyError inside is not "bad input"


def test_closed_pipe_ends_quietly():
    proc = subprocess.Popen(
        [sys.executable, "-m", "formation_ftc.cli", "check", SCN, "--json"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    proc.stdout.close()  # like `| head` that has already exited
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 0 and b"Traceback" not in err and b"BrokenPipe" not in err, (
        err.decode()[-2000:]
    )


def test_campaign_hostile_input_exits_2(tmp_path, capsys):
    from formation_ftc.campaign.cli import main as campaign_main

    out = str(tmp_path / "c")
    for args, fragment in [
        (["--runs", "1e9"], "invalid int value"),
        (["--runs", "1000000000"], "less than or equal to 10000000"),
        (["--max-campaign-steps", "1e5"], "run-steps in total exceed the budget"),
        (["--max-memory", "1KB"], "a batch of"),
    ]:
        with pytest.raises(SystemExit) if fragment == "invalid int value" else _nullcontext():
            assert campaign_main(["run", "cw-pd-gains", "--out", out, "--no-progress", *args]) == 2
        err = capsys.readouterr().err
        assert fragment in err and "Traceback" not in err, (args, err)
    assert campaign_main(["run", "cw-pd-gains", "--out", "", "--no-progress"]) == 2
    assert "--out: empty path" in capsys.readouterr().err
    deep = tmp_path / "deep.toml"
    deep.write_text(DEEP_TOML)
    assert campaign_main(["run", str(deep), "--out", out]) == 2
    assert "nested more than 32 levels" in capsys.readouterr().err
    assert not Path(out).exists()
    assert campaign_main(["report", str(tmp_path / "nothing-here")]) == 2
    # a constant error in an override fails validation, not the first chunk
    import tomli_w

    bad = tmp_path / "div0.toml"
    bad.write_text(
        tomli_w.dumps(
            {
                "campaign": {"name": "div0", "base": "cw-pd-fault", "runs": 2, "chunk_size": 2},
                "overrides": {"simulation.horizon": 2.0, "actuator.bias": ["1/0", "0", "0"]},
            }
        )
    )
    assert campaign_main(["run", str(bad), "--out", out, "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert (
        "actuator.bias" in err and "division by a constant zero" in err and "Traceback" not in err
    )
    assert not Path(out).exists()


class _nullcontext:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def test_metrics_json_of_a_diverged_run_names_a_state_not_an_accumulator(tmp_path, capsys):
    assert (
        main(
            [
                "run",
                SCN,
                "--set",
                "simulation.horizon=60",
                "--set",
                "controller.kp=1e6",
                "--out",
                str(tmp_path / "o"),
            ]
        )
        == 1
    )
    err = capsys.readouterr().err
    assert "simulation diverged" in err
    assert "delta_v" not in err and "effort" not in err and "'dv'" not in err
    assert json.loads((tmp_path / "o" / "metrics.json").read_text())["scenario"] == SCN


def test_path_texts_the_system_refuses_exit_2(tmp_path, capsys):
    from formation_ftc.campaign.cli import main as campaign_main

    long = "a" * 5000
    for call in (
        lambda: main(["show", long]),
        lambda: main(["check", long + ".toml"]),
        lambda: main(["run", SCN, *SHORT, "--out", long]),
        lambda: campaign_main(["run", long, "--out", str(tmp_path / "c")]),
        lambda: campaign_main(["report", long]),
    ):
        assert call() == 2
        err = capsys.readouterr().err
        assert "File name too long" in err and "Traceback" not in err and len(err) < 400


class _FullStream:
    """A stderr whose every write fails like a full disk (ENOSPC)."""

    encoding = "utf-8"

    def write(self, text):
        raise OSError(28, "No space left on device")

    def flush(self):
        raise OSError(28, "No space left on device")

    def isatty(self):
        return False


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
@pytest.mark.parametrize("stream", ["stderr", "stdout"])
def test_a_full_stderr_or_stdout_costs_no_result(stream, tmp_path):
    out = tmp_path / "run"
    with open("/dev/full", "w") as full:
        proc = subprocess.run(
            [sys.executable, "-m", "formation_ftc.cli", "run", SCN, *SHORT, "--out", str(out)],
            **{stream: full},
            timeout=600,
        )
    assert proc.returncode == 0
    assert (
        (out / "result.nc").is_file()
        and (out / "metrics.json").is_file()
        and (out / "index.html").is_file()
    )


def test_a_full_stderr_costs_no_campaign_chunk_nor_error_status(tmp_path, monkeypatch):
    from formation_ftc.campaign import runner
    from formation_ftc.campaign.cli import main as campaign_main

    spec = tmp_path / "c.toml"
    spec.write_text(
        '[campaign]\nname = "full"\nbase = "cw-pd-fault"\nruns = 2\nchunk_size = 2\n'
        '[overrides]\n"simulation.horizon" = 20.0\n'
        '[sample]\n"controller.kp" = {dist = "uniform", low = 1.0, high = 3.0}\n'
    )
    store = runner._store_chunk

    def log_then_store(*a):
        print("a log line nobody can read", file=sys.stderr)
        return store(*a)

    monkeypatch.setattr(runner, "_store_chunk", log_then_store)
    monkeypatch.setattr(sys, "stderr", _FullStream())
    assert (
        campaign_main(["run", str(spec), "--out", str(tmp_path / "c"), "--workers", "1"]) == 0
    )  # progress on
    assert (
        main(["campaign", "run", str(spec), "--out", str(tmp_path / "c"), "--workers", "1"]) == 0
    )  # resumed
    assert main(["show", "no-such-scenario"]) == 2  # the error line is lost, not the exit status
    assert len(list((tmp_path / "c" / "chunks").glob("*.parquet"))) == 1
