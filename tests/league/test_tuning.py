"""``formation-ftc tune`` (formation_ftc.league.tuning): the LQR oracle, the ``[tune]`` table and field
checks, the league's paired replicates, and one end-to-end command on a tiny league with its tuned
leaderboard column."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from scipy.linalg import solve_continuous_are

from formation_ftc.league.definition import LeagueError, load_league, method_tune
from formation_ftc.league.tuning import (
    TuneError,
    TuneField,
    build_problem,
    minimise,
    penalised_objective,
    replicate_raws,
)

MASS = 10.0  # kg
Q, R = 1.0, 1.0  # weights of |x|^2 [1/m^2] and |F|^2 [1/N^2]
HORIZON = 60.0  # s


def _double_integrator(x0: list[float], kp: float, kd: float) -> dict:
    """One spacecraft on CW dynamics about a 1e10 m orbit (mean motion 2e-8 rad/s: three decoupled
    double integrators) under PD feedback F = -kp x - kd v [N], with the cost integrals as metrics."""
    return {
        "scenario": {"name": "lqr-oracle", "method": "composed"},
        "simulation": {"horizon": HORIZON, "dt": 0.1, "record_every": 600},
        "plant": {
            "type": "clohessy-wiltshire",
            "semi_major_axis": 1e10,
            "mass": [MASS],
            "initial_position": [x0],
        },
        "controller": {"type": "pd", "kp": kp, "kd": kd, "nominal_mass": MASS},
        "metrics": [
            # RMS of |x| over the 600 steps: HORIZON * rms^2 = int |x|^2 dt by the rectangle rule (its
            # O(dt) error dt/2 |x0|^2 does not depend on the gains)
            {
                "name": "position_rms",
                "signal": "position_error",
                "reduce": "rms",
                "norm": True,
                "spacecraft": "sum",
                "units": "m",
            },
            # int |F|^2 dt, integrated with the plant (RK4)
            {
                "name": "effort",
                "signal": "control_effort",
                "reduce": "final",
                "spacecraft": "sum",
                "units": "N2 s",
            },
        ],
    }


@pytest.mark.parametrize("optimiser", ["nelder-mead", "gradient"])
def test_tuning_recovers_the_lqr_gains(optimiser):
    """Oracle: PD gains (kp, kd) tuned to minimise J = sum over three initial conditions of
    int (Q |x|^2 + R |F|^2) dt on a double integrator (m = 10 kg) are the LQR gains of that cost,
    K = R^-1 B^T P from the continuous algebraic Riccati equation: LQR minimises x0^T P x0 for every x0
    at once, so the sum over initial conditions has the same minimiser. Tolerance 2 % on each gain:
    the differences are the finite horizon (60 s, 13 closed-loop time constants: e^-26 of the cost
    left), the rectangle rule on int |x|^2 (O(dt^2) gain-dependent, (omega_n dt)^2 ~ 1e-3), and the
    optimiser's tolerance on a cost that is flat (quadratic) at its minimum -- J moves by 1e-4
    relative for a 1 % gain error, hence xatol 1e-4 on the log-scaled gains; measured: well under
    1 %. Starting 3x and 0.3x away from the optimum, the optimiser must move the gains."""
    A = np.array([[0.0, 1.0], [0.0, 0.0]])
    B = np.array([[0.0], [1.0 / MASS]])
    P = solve_continuous_are(A, B, np.diag([Q, 0.0]), np.array([[R]]))
    kp_star, kd_star = (np.linalg.solve(np.array([[R]]), B.T @ P)).ravel()
    raws = [
        _double_integrator(x0, kp=3.0 * kp_star, kd=0.3 * kd_star)
        for x0 in ([1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [-1.0, 0.5, 1.5])
    ]
    fields = [
        TuneField("controller.kp", 0.1, 10.0, log=True),
        TuneField("controller.kd", 0.5, 50.0, log=True),
    ]
    problem = build_problem(raws, fields)
    J = penalised_objective(
        lambda m: Q * HORIZON * m["position_rms"] ** 2 + R * m["effort"], statistic="mean"
    )
    out = minimise(problem, J, optimiser=optimiser, max_evaluations=150, tolerance=1e-6)
    kp, kd = out.gains
    assert kp == pytest.approx(kp_star, rel=0.02), (kp, kp_star, out.message)
    assert kd == pytest.approx(kd_star, rel=0.02), (kd, kd_star, out.message)
    assert out.value < out.initial_value
    # the value at the optimum is x0^T P x0 summed (the cost of the optimal policy), mean over the runs
    x0s = np.array([[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [-1.0, 0.5, 1.5]])
    expected = np.mean([sum(P[0, 0] * x**2 for x in x0) for x0 in x0s])
    dt_bias = 0.5 * 0.1 * Q * np.mean(np.sum(x0s**2, axis=1))  # the rectangle rule's dt/2 |x0|^2
    assert out.terms["objective"] == pytest.approx(expected + dt_bias, rel=0.01)


def test_penalty_counts_violations_and_diverged_runs():
    import jax.numpy as jnp

    J = penalised_objective(
        "dv", requirement=("err", 1.0), margin=0.5, penalty=2.0, bad_run_penalty=7.0, scale=1.0
    )
    metrics = {"dv": jnp.array([1.0, 1.0, 5.0]), "err": jnp.array([0.25, 0.75, jnp.nan])}
    value, terms = J(metrics, jnp.array([False, False, True]))
    # run 0 meets 0.5 m; run 1 exceeds the tightened 0.5 m by 50 % but passes 1 m; run 2 diverged
    assert float(terms["violation"]) == pytest.approx((0.0 + 0.5 + 7.0) / 3)
    assert float(terms["fail_fraction"]) == pytest.approx(1 / 3)
    assert float(terms["objective"]) == pytest.approx(1.0)  # a diverged run counts as f0 = scale
    assert float(value) == pytest.approx(1.0 + 2.0 * 7.5 / 3)


def test_a_run_far_from_the_requirement_counts_as_one_failure():
    """The violation cap: a run 10 times over the requirement weighs what a run twice over it does (one
    failure), so gains cannot buy a large error reduction on hopeless runs with failures elsewhere;
    below the cap the penalty keeps its slope. ``inf`` restores the uncapped L1 penalty."""
    import jax.numpy as jnp

    metrics = {"dv": jnp.array([1.0, 1.0, 1.0]), "err": jnp.array([0.5, 1.5, 10.0])}
    ok = jnp.array([False, False, False])
    capped = penalised_objective("dv", requirement=("err", 1.0), margin=0.0, penalty=1.0)
    uncapped = penalised_objective(
        "dv", requirement=("err", 1.0), margin=0.0, penalty=1.0, violation_cap=float("inf")
    )
    assert float(capped(metrics, ok)[1]["violation"]) == pytest.approx((0.0 + 0.5 + 1.0) / 3)
    assert float(uncapped(metrics, ok)[1]["violation"]) == pytest.approx((0.0 + 0.5 + 9.0) / 3)
    with pytest.raises(TuneError, match="violation_cap"):
        penalised_objective("dv", requirement=("err", 1.0), violation_cap=0.0)


def test_fields_that_are_not_leaves_are_rejected():
    raw = _double_integrator([1.0, 0.0, 0.0], kp=1.0, kd=5.0)
    # the plant holds its mean motion, derived from the orbit radius
    with pytest.raises(TuneError, match=r"'plant\.semi_major_axis': not a numeric leaf"):
        build_problem([raw], [TuneField("plant.semi_major_axis", 1e9, 1e11)])
    with pytest.raises(TuneError, match=r"'controller\.type'.*not one finite number"):
        build_problem([raw], [TuneField("controller.type", 0.0, 1.0)])
    with pytest.raises(TuneError, match=r"'controller\.kp': the paper value 1 lies outside"):
        build_problem([raw], [TuneField("controller.kp", 2.0, 3.0)])
    with pytest.raises(TuneError, match=r"'controller\.ki': the scenario has no such field"):
        build_problem([raw], [TuneField("controller.ki", 2.0, 3.0)])
    with pytest.raises(TuneError, match=r"'controller\.kp': log scale needs low > 0"):
        TuneField("controller.kp", 0.0, 3.0, log=True)


def test_a_rebuilt_field_gives_the_runs_its_builder_gives():
    """``rebuild``: a field the builder derives parameters from (the plant's mean motion from its orbit
    radius) is tuned by building the runs again. Oracle: the scenario built and simulated directly with
    the same values, for a rebuilt field alone and with a leaf field beside it; the gradient optimiser,
    which cannot differentiate a rebuild, is refused."""
    from formation_ftc.api import load_scenario, simulate_with_metrics
    from formation_ftc.config.loader import apply_overrides

    raws = [_double_integrator(x0, kp=1.0, kd=5.0) for x0 in ([1.0, 0.0, 0.0], [0.0, 2.0, 0.0])]
    orbit = TuneField("plant.semi_major_axis", 1e6, 1e11, log=True, rebuild=True)
    for fields, theta in (
        ([orbit], [7.0e6]),
        ([TuneField("controller.kp", 0.1, 10.0), orbit], [2.0, 7.0e6]),
    ):
        problem = build_problem(raws, fields)
        metrics, diverged = problem.evaluate(theta)
        assert not diverged.any()
        values = {f.path: v for f, v in zip(fields, theta, strict=True)}
        for j, raw in enumerate(raws):
            _, direct = simulate_with_metrics(load_scenario(apply_overrides(dict(raw), values)))
            for name in ("position_rms", "effort"):
                assert metrics[name][j] == pytest.approx(direct[name], rel=1e-12)
        at_paper, _ = problem.evaluate(problem.initial)
        assert not np.allclose(at_paper["position_rms"], metrics["position_rms"])  # the CW coupling
    J = penalised_objective("effort")
    with pytest.raises(TuneError, match="rebuilt at each evaluation"):
        minimise(problem, J, optimiser="gradient", max_evaluations=3)
    with pytest.raises(TuneError, match="no traced form"):
        problem.outputs(problem.initial)


def test_a_rebuilt_field_the_builder_ignores_is_refused(tmp_path, tiny_league):
    """gui2022-cof2tc with the printed K: its CARE weight changes nothing, so tuning it is an error."""
    from formation_ftc.league.tuning import tune_league_method

    path = tiny_league(tmp_path, methods=("gui2022-cof2tc",))
    mfile = tmp_path / "translational" / "gui2022-cof2tc.toml"
    raw = tomllib.loads(mfile.read_text())
    raw["controller"].update(gains="printed", K=[[0.0063, 0, 0, 0.1127, 0, 0]] * 3)
    mfile.write_text(tomli_w.dumps(raw))
    with pytest.raises(
        TuneError, match=r"'controller\.care_q_scale': another value changes nothing"
    ):
        tune_league_method(
            path, "gui2022-cof2tc", "limited", cases=["none"], train_seeds=1, holdout_seeds=1
        )


def _league_with_tune(tmp_path: Path, tiny_league, method: str, tune: dict) -> Path:
    path = tiny_league(tmp_path, methods=(method,))
    mfile = tmp_path / "translational" / f"{method}.toml"
    raw = tomllib.loads(mfile.read_text())
    raw["tune"] = tune
    mfile.write_text(tomli_w.dumps(raw))
    return path


@pytest.mark.parametrize(
    ("tune", "message"),
    [
        ({"fields": {"controller.K3": [0.001, 0.1]}}, r"tune\.fields\.controller\.K3: the method file sets no K3"),
        ({"fields": {"controller.K1": [0.1, 0.01]}}, r"controller\.K1: bounds \[0\.1, 0\.01\] need low < high"),
        ({"fields": {"controller.K1": [0.01, 0.1]}}, r"controller\.K1: the paper value 0\.005 lies outside"),
        ({"fields": {"truth.mass": [1, 2]}}, r"truth\.mass: give 'slot\.field' of a slot the method owns"),
        ({"fields": {"controller.K1": {"low": 0.0, "high": 0.1, "log": True}}}, r"controller\.K1: a log scale needs low > 0"),
        ({"fields": {"controller.K1": [0.001, 0.1]}, "objective": "fuel"}, r"tune\.objective = 'fuel': not a metric"),
        ({"fields": {"controller.K1": [0.001, 0.1]}, "weights": 1}, r"tune: weights"),
    ],
)  # fmt: skip
def test_tune_table_errors_name_the_field(tmp_path, tiny_league, tune, message):
    spec = load_league(_league_with_tune(tmp_path, tiny_league, "yang2013", tune))
    with pytest.raises(LeagueError, match=message):
        method_tune(spec, spec.method("yang2013"))


def test_builtin_tune_tables_validate():
    spec = load_league("translational")
    tables = {m.name: method_tune(spec, m) for m in spec.methods}
    assert {n for n, t in tables.items() if t is not None} >= {"yang2013", "li2020-thm1", "sir-ftc"}
    # derived gains (Bryson's maxima -> Riccati gain, the CARE weight -> K): tuned by rebuilding
    for method in ("lqr", "gui2022-cof2tc", "gui2022-lof2tc"):
        assert all(b.rebuild for b in tables[method].fields.values()), method
    assert all(t is not None for t in tables.values())  # every translational method is tunable
    attitude = load_league("attitude")
    tuned = {m.name for m in attitude.methods if method_tune(attitude, m) is not None}
    assert tuned == {"mehrabian", "mehrabian-active", "pd", "yang2013"}


def test_replicates_are_paired_and_drawn_as_the_league_draws_them(tmp_path, tiny_league):
    from formation_ftc.campaign.sampling import run_seed
    from formation_ftc.league.runner import plan_cells

    spec = load_league(tiny_league(tmp_path, methods=("yang2013",)))
    cells = [c for c in plan_cells(spec, ["yang2013"])["yang2013"] if c.level == "limited"][:2]
    raws, labels = replicate_raws(spec, "yang2013", cells, [0, 1, 10_000])
    assert [lb["replicate"] for lb in labels] == [0, 1, 10_000] * 2
    assert {lb["case"] for lb in labels[:3]} == {cells[0].case}
    for j in range(3):  # paired: the same seed, initial-error seed and onset in both cells
        a, b = raws[j], raws[3 + j]
        assert a["simulation"]["seed"] == b["simulation"]["seed"]
        assert a["plant"]["dispersion_seed"] == b["plant"]["dispersion_seed"]
        assert a["actuator"]["onset"] == b["actuator"]["onset"]
        assert 30.0 <= a["actuator"]["onset"] <= 40.0
    assert raws[0]["simulation"]["seed"] == run_seed(spec.league.seed, 0)
    assert len({r["plant"]["dispersion_seed"] for r in raws[:3]}) == 3  # replicates differ


def test_tune_command_end_to_end_and_tuned_column(tmp_path, tiny_league, capsys):
    """The command on a tiny league (60 s, one case, one seed per set, three evaluations): a result
    with provenance, gains within bounds, the held-out paper-gain runs; the leaderboard's ranking rows
    get the tuned column from it, "not tuned" for a method without a result."""
    from formation_ftc.cli import main
    from formation_ftc.league.report import tuned_column

    league = tiny_league(tmp_path, methods=("yang2013",))
    out = tmp_path / "tuned"
    argv = ["tune", "yang2013", "--league", str(league), "--level", "limited", "--cases", "bias"]
    argv += ["--train-seeds", "1", "--holdout-seeds", "2", "--max-evaluations", "3"]
    assert main([*argv, "--out", str(out)]) == 0
    result = json.loads((out / "yang2013--limited.json").read_text())
    assert result["kind"] == "formation-ftc tuning" and result["cases"] == ["bias"]
    assert result["provenance"] and result["optimiser"]["name"] == "nelder-mead"
    assert result["optimiser"]["evaluations"] <= 4  # the budget (+ the start, when not evaluated)
    assert result["paper_gains"] == {"controller.K1": 0.005, "controller.K2": 0.01}
    for f in result["fields"]:
        assert f["low"] <= result["tuned_gains"][f["path"]] <= f["high"]
    assert result["J"]["tuned"] <= result["J"]["paper"]
    assert result["holdout"]["paper"]["runs"] == 2 and result["holdout"]["replicates"] == [0, 1]
    assert result["train"]["replicates"] == [10_000, 10_000]
    # fresh replicates: neither the league's (0 .. 99) nor the training's (10,000)
    fresh = result["fresh"]
    assert fresh["replicates"] == [10_001, 10_002] and fresh["tuned"]["runs"] == 2
    for block in (result["train"], result["holdout"], fresh):
        for s in (block["paper"], block["tuned"]):  # every mean says what it covers
            assert s["finished"] + s["left_out"] == s["runs"]
            assert s["finished"] >= s["runs"] - s["diverged"] - s["left_out"]
    printed = capsys.readouterr().out
    assert "yang2013 @ limited" in printed and "fresh: pass rate" in printed
    # given gains: no training, the same held-out paper runs, the gains not given keep the paper's
    out2 = tmp_path / "given"
    assert main([*argv, "--gains", "controller.K1=0.004", "--out", str(out2)]) == 0
    given = json.loads((out2 / "yang2013--limited.json").read_text())
    assert given["given_gains"] and given["train"] is None and given["J"] is None
    assert given["tuned_gains"] == {"controller.K1": 0.004, "controller.K2": 0.01}
    assert given["holdout"]["paper"] == result["holdout"]["paper"]
    assert given["fresh"]["paper"] == result["fresh"]["paper"]
    for bad in ("controller.K1", "controller.nope=1", "controller.K1=x"):
        assert main([*argv, "--gains", bad, "--out", str(tmp_path / "bad")]) == 2, bad
    rank = {
        "limited": [{"method": "yang2013"}, {"method": "lqr"}],
        "unsaturated": [{"method": "yang2013"}],
    }
    assert tuned_column(rank, out) == 1
    text = rank["limited"][0]["tuned"]
    assert text.startswith("K1 ") and "held-out pass rate" in text and "(paper" in text
    assert "fresh-seed pass rate" in text
    assert rank["limited"][1]["tuned"] == "not tuned"
    assert rank["unsaturated"][0]["tuned"] == "not tuned"  # tuned at another level
    # a method without a [tune] table: exit code 2, named
    (tmp_path / "l").mkdir()
    lqr_league = tiny_league(tmp_path / "l", methods=("lqr",))
    lqr_file = tmp_path / "l" / "translational" / "lqr.toml"
    lqr_file.write_text(
        tomli_w.dumps({k: v for k, v in tomllib.loads(lqr_file.read_text()).items() if k != "tune"})
    )
    assert main(["tune", "lqr", "--league", str(lqr_league), "--out", str(out)]) == 2
    assert "has no [tune] table" in capsys.readouterr().err


def test_tuning_flies_at_the_step_the_league_check_chose(tmp_path, tiny_league):
    """With the league's step check on, tune flies the method at the check's chosen step; a check a
    league run recorded (league.json ``step_check``) is reused, not run again, and is recorded."""
    from formation_ftc.league.tune_cli import _league_step_checks
    from formation_ftc.league.tuning import tune_league_method

    league = tiny_league(tmp_path, methods=("yang2013",), step_check={"enabled": True})
    record = {"chosen_dt": 0.1, "converged": True, "changes": [0.001], "dts": [0.2, 0.1]}
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "league.json").write_text(json.dumps({"step_check": {"yang2013": record}}))
    reused = _league_step_checks(str(tmp_path / "run"))
    result = tune_league_method(
        league,
        "yang2013",
        "limited",
        cases=["bias"],
        train_seeds=1,
        holdout_seeds=1,
        max_evaluations=2,
        step_checks=reused,
    )
    assert result["dt"] == 0.1 and result["step_check"] == record
    with pytest.raises(TuneError, match="--step-check-from"):
        _league_step_checks(str(tmp_path / "nowhere"))
