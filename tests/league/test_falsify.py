"""`formation-ftc falsify` on a tiny league: the search finds a violating run, writes it as a
scenario that `formation-ftc run` replays to the same robustness (bit for bit), is reproducible from
its seed, maps the unit cube into the stated ranges, and refuses bad input naming it."""

from __future__ import annotations

import json

import numpy as np
import pytest

from formation_ftc import api
from formation_ftc.cli import main
from formation_ftc.league.definition import load_league
from formation_ftc.league.falsify import COORDINATES, candidate_raw, falsify
from formation_ftc.league.runner import plan_cells


def test_falsify_finds_writes_and_replays(tmp_path, tiny_league):
    league = tiny_league(tmp_path, methods=("lqr",))
    out = tmp_path / "f"
    argv = ["-q", "falsify", "lqr", "--league", str(league), "--level", "limited"]
    assert main([*argv, "--budget", "8", "--population", "4", "--out", str(out)]) == 0
    (result,) = out.glob("*.json")
    rec = json.loads(result.read_text())
    assert rec["kind"] == "formation-ftc falsification" and rec["provenance"]
    assert rec["found"] and 1 <= rec["runs_to_violation"] <= rec["runs"] <= 8
    assert rec["robustness"] < 0 and rec["fault"]["kind"]
    # the falsifying scenario replays to the same robustness
    _, metrics = api.simulate_with_metrics(
        api.load_scenario(rec["scenario"]), raise_on_divergence=False
    )
    assert -metrics["stl_violation"] == rec["robustness"]
    # same seed, same search
    a = falsify(str(league), "lqr", "limited", budget=4, population=4, optimizer="random", seed=3)
    b = falsify(str(league), "lqr", "limited", budget=4, population=4, optimizer="random", seed=3)
    assert a.history == b.history and a.fault == b.fault


def test_the_cube_maps_into_the_stated_ranges(tmp_path, tiny_league):
    spec = load_league(tiny_league(tmp_path, methods=("lqr",)))
    cells = {c.fault_kind: c for c in plan_cells(spec, ["lqr"])["lqr"] if c.level == "limited"}
    rng = np.random.default_rng(0)
    kinds = set()
    for u in [np.zeros(len(COORDINATES)), np.ones(len(COORDINATES)), *rng.random((40, 12))]:
        raw, fault = candidate_raw(spec, cells, "limited", u)
        kinds.add(fault["kind"])
        act = raw["actuator"]
        assert (
            act["kind"] == fault["kind"] and 1 <= act["spacecraft"] <= 4 and 0 <= act["axis"] <= 2
        )
        assert spec.league.onset.low <= act["onset"] <= spec.league.onset.high
        assert abs(act.get("bias", 0.0)) <= 0.2 and 0 <= act.get("effectiveness", 1.0) <= 1
        assert raw["plant"]["dispersion_seed"] == fault["initial_error_seed"] < 2**31
        assert raw["simulation"]["seed"] == fault["noise_seed"]
    assert kinds == {
        "loss_of_effectiveness",
        "bias",
        "stuck",
        "outage",
        "intermittent",
        "degrading",
    }


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--budget", "0"], "--budget"),
        (["--level", "fast"], "--level 'fast'"),
        (["--population", "1"], "--population 1"),
    ],
)
def test_bad_input_is_refused(tmp_path, tiny_league, capsys, extra, message):
    league = tiny_league(tmp_path, methods=("lqr",))
    argv = ["falsify", "lqr", "--league", str(league), "--out", str(tmp_path / "o"), *extra]
    assert main(argv) == 2
    assert message in capsys.readouterr().err
    assert main(["falsify", "nope", "--league", str(league), "--out", str(tmp_path / "o")]) == 2


def test_kind_and_min_magnitude_bracket_the_breaking_severity(tmp_path, tiny_league, capsys):
    """``--kind`` restricts the search; ``--min-magnitude`` brackets each kind's smallest breaking
    severity at its worst run: the bracket's ends are samples of the opposite verdicts, and a sample
    replayed alone (a single compiled run, not the batch) has the same robustness, bit for bit."""
    from formation_ftc.league.falsify import _raw_of, _with_severity

    league = tiny_league(tmp_path, methods=("lqr",))
    out = tmp_path / "m"
    argv = ["falsify", "lqr", "--league", str(league), "--level", "limited", "--out", str(out)]
    extra = ["--kind", "loss_of_effectiveness,stuck", "--min-magnitude", "--rounds", "2"]
    assert main([*argv, "--budget", "4", "--population", "4", "--optimizer", "random", *extra]) == 0
    assert "loss_of_effectiveness: lost effectiveness" in capsys.readouterr().out
    rec = json.loads(next(out.glob("*.json")).read_text())
    assert set(rec["kinds"]) <= {"loss_of_effectiveness", "stuck"}
    by_kind = {m["kind"]: m for m in rec["min_magnitude"]}
    assert set(by_kind) == {"loss_of_effectiveness", "stuck"}
    assert by_kind["stuck"]["severity"] is None  # no magnitude
    loe = by_kind["loss_of_effectiveness"]
    samples = dict(map(tuple, loe["samples"]))
    assert 4 <= loe["runs"] == len(samples) <= 8
    if loe["largest_holding"] is not None:
        assert samples[loe["largest_holding"]] >= 0
    if loe["smallest_violating"] is not None:
        assert samples[loe["smallest_violating"]] < 0
    s, rho = next(iter(samples.items()))
    spec = load_league(league)
    cells = {c.fault_kind: c for c in plan_cells(spec, ["lqr"])["lqr"] if c.level == "limited"}
    fault = rec["worst_by_kind"]["loss_of_effectiveness"]["fault"]  # drawn by this seed's search
    raw = _with_severity(_raw_of(spec, cells, fault), fault, s)
    _, metrics = api.simulate_with_metrics(api.load_scenario(raw), raise_on_divergence=False)
    assert -metrics["stl_violation"] == rho
    assert main([*argv, "--kind", "nope"]) == 2
    assert "--kind 'nope'" in capsys.readouterr().err
