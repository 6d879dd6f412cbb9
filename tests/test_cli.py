"""The command line end to end (in-process)."""

import json

from formation_ftc.cli import main


def test_list_show_check_run(tmp_path, capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    assert "cw-free-drift" in out
    assert main(["show", "cw-pd-fault", "--set", "simulation.horizon=50"]) == 0
    assert "horizon = 50.0" in capsys.readouterr().out
    assert main(["check", "cw-pd-fault", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["all_required_hold"] is True
    # a destabilising negative-stiffness design is not allowed by the schema (kp >= 0) -> exit 2
    assert main(["check", "cw-pd-fault", "--set", "controller.kp=-1"]) == 2
    assert "controller.kp" in capsys.readouterr().err
    out_dir = tmp_path / "run"
    assert (
        main(["run", "cw-pd-fault", "--out", str(out_dir), "--set", "simulation.horizon=20"]) == 0
    )
    assert (out_dir / "result.nc").exists() and (out_dir / "index.html").exists()
    assert not list(out_dir.glob("*.png"))  # figures only with --figures or `formation-ftc plot`
    metrics = json.loads((out_dir / "metrics.json").read_text())
    assert metrics["scenario"] == "cw-pd-fault" and "delta_v_total" in metrics


def test_run_divergence_exit_code_keeps_partial(tmp_path, capsys):
    code = main(
        [
            "run",
            "cw-pd-fault",
            "--out",
            str(tmp_path),
            "--set",
            "simulation.horizon=60",
            "--set",
            "controller.kp=1e9",
        ]
    )
    assert code == 1
    assert (tmp_path / "result.nc").exists()
    assert "diverged" in capsys.readouterr().err


def test_a_failing_divergence_replay_keeps_the_partial_result(tmp_path, capsys, monkeypatch):
    """The replay that names the diverged variable is a diagnostic: when it fails, the run is still
    reported (step and time only) and its partial result written, as in campaigns."""
    import formation_ftc.sim.engine as engine

    def broken(*args, **kwargs):
        raise RuntimeError("replay failed")

    monkeypatch.setattr(engine, "diagnose_divergence", broken)
    argv = ["run", "cw-pd-fault", "--out", str(tmp_path), "--set", "simulation.horizon=60"]
    assert main([*argv, "--set", "controller.kp=1e9"]) == 1
    assert (tmp_path / "result.nc").exists()
    err = capsys.readouterr().err
    assert "diverged" in err and "<state>" in err


def test_check_fails_for_unstable_design(capsys):
    # free drift needs no condition; a pd loop with zero damping and gains -> marginal: max Re = 0
    assert (
        main(["check", "cw-pd-fault", "--set", "controller.kd=0", "--set", "controller.kp=0"]) == 1
    )


def test_check_json_for_every_builtin_scenario(capsys):
    """`check --json` is valid JSON for every built-in scenario (numpy values included)."""
    from formation_ftc.api import list_scenarios

    for name in list_scenarios():
        code = main(["check", name, "--json"])
        data = json.loads(capsys.readouterr().out)
        assert code == (0 if data["all_required_hold"] else 1), name
        for c in data["conditions"]:
            assert c["holds"] in (True, False, None)
