"""The translational league's navigation axis: at the filtered level every law flies on a navigation
filter (the league's, or its own residual FDI's Kalman filter; an observer reads the league's filter
too), gets the level's flight knowledge of the same thrusters, and is scored for consistency (NEES,
NIS); bad definitions are refused naming the field."""

from __future__ import annotations

import tomllib

import numpy as np
import pandas as pd
import pytest
import tomli_w

from formation_ftc.league.definition import LeagueError, load_league
from formation_ftc.league.runner import NAVIGATION_METRICS, plan_cells, run_league


@pytest.fixture(scope="module")
def cells():
    return plan_cells(load_league("translational"))


def test_every_method_but_the_observer_flies_filtered(cells):
    spec = load_league("translational")
    level = next(lv for lv in spec.levels if lv.navigation == "filtered")
    assert level.saturation == 0.2 and level.method_fields_from == "limited"
    for name, cs in cells.items():
        filtered = [c for c in cs if c.level == level.name]
        assert filtered, name
        est = filtered[0].raw["estimator"]
        limited = next(c for c in cs if c.level == "limited" and c.case == filtered[0].case)
        if est["type"] == "iterative-learning-observer":  # the observer reads the league's filter
            assert est["navigation"] == spec.navigation_filter
            assert {k: v for k, v in est.items() if k != "navigation"} == limited.raw["estimator"]
        elif est["type"] == "residual-fdi":  # its own Kalman filter navigates
            assert est["fly_on_filter"] is True and est["residual"] == "kalman"
            # the same flight knowledge of the 0.2 N thrusters as at the limited level
            assert {k: v for k, v in est.items() if k != "fly_on_filter"} == limited.raw[
                "estimator"
            ]
        else:
            assert est == spec.navigation_filter
            assert "estimator" not in limited.raw
        assert filtered[0].raw["actuator"] == limited.raw["actuator"]
        assert "navigation-consistency" in [e["type"] for e in filtered[0].raw["evaluations"]]
        assert {m["name"] for m in NAVIGATION_METRICS} <= {
            m["name"] for m in filtered[0].raw["metrics"]
        }
        assert "navigation-consistency" not in [e["type"] for e in limited.raw["evaluations"]]


def test_the_observer_and_the_law_read_the_filter(cells):
    # gui2022-lof2tc's filtered cell: its ILO reads the league filter's estimate (e_y = x_hat - q_hat)
    # and its law tracks with it (e_y = q0 - x_hat): the identities of the chain, on recorded signals
    from formation_ftc.api import load_scenario, simulate

    cell = next(
        c for c in cells["gui2022-lof2tc"] if c.level == "limited-filtered" and c.case == "none"
    )
    ds = simulate(
        load_scenario(cell.raw, {"simulation.horizon": 4.0, "simulation.record_every": 1})
    )
    x_hat = ds["navigation_estimate"].values
    np.testing.assert_allclose(
        ds["estimation_error"].values, x_hat - ds["estimate"].values, rtol=0, atol=1e-12
    )
    np.testing.assert_allclose(
        ds["tracking_error"].values, ds["desired_state"].values - x_hat, rtol=0, atol=1e-12
    )
    noise = ds["navigation_estimate"].values[:, :, :3] - ds["position"].values
    assert np.abs(noise).max() < 1.0  # the filter follows the truth (0.1 m sensors)


def test_the_observers_filter_names_its_own_fields(cells):
    import copy

    from formation_ftc.api import load_scenario

    raw = copy.deepcopy(
        next(c for c in cells["gui2022-lof2tc"] if c.level == "limited-filtered").raw
    )
    raw["estimator"]["navigation"]["nominal_mass"] = [100.0]
    with pytest.raises(ValueError, match="estimator.navigation.nominal_mass: 1 values for 4"):
        load_scenario(raw)


def test_tiny_league_scores_the_filter(tmp_path, tiny_league):
    path = tiny_league(tmp_path, methods=("lqr",), filtered=True)
    out = tmp_path / "out"
    run_league(path, out, seeds=1, methods=["lqr"])
    from formation_ftc.league.report import write_leaderboard

    board = write_leaderboard(out, plots=False)
    assert "limited-filtered" in board["ranking"]
    runs = pd.read_parquet(out / "leaderboard" / "runs.parquet")
    filt = runs[runs.level == "limited-filtered"]
    assert len(filt) and (filt.status == "ok").all()
    for name in ("mean_nees", "nees_in_band", "nis_in_band"):
        v = filt[f"metric:{name}"].to_numpy(dtype=float)
        assert np.isfinite(v).all() and (v >= 0).all(), name
    assert ((filt["metric:nis_in_band"] >= 0) & (filt["metric:nis_in_band"] <= 1)).all()
    assert runs[runs.level == "limited"]["metric:mean_nees"].isna().all()


def _write(tmp_path, edit) -> str:
    from formation_ftc.league.definition import builtin_leagues

    src = builtin_leagues()["translational"]
    raw = tomllib.loads(src.read_text())
    edit(raw)
    (tmp_path / "translational").mkdir(exist_ok=True)
    for m in raw["methods"]:
        (tmp_path / m["scenario"]).write_text((src.parent / m["scenario"]).read_text())
    path = tmp_path / "l.toml"
    path.write_text(tomli_w.dumps(raw))
    return str(path)


def test_an_observer_needs_the_relative_navigation_filter(tmp_path):
    def edit(raw):
        raw["navigation_filter"]["type"] = "scripted-fdi"

    with pytest.raises(
        LeagueError, match="(?s)gui2022-lof2tc cannot run .* on a relative-navigation-f"
    ):
        plan_cells(load_league(_write(tmp_path, edit)), methods=["gui2022-lof2tc"])


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda raw: raw.pop("navigation_filter"), r"navigation_filter"),
        (lambda raw: raw["levels"][2].update(method_fields_from="fast"), r"method_fields_from"),
        (lambda raw: raw["levels"][2].update(navigation="kalman"), r"navigation"),
    ],
)
def test_bad_navigation_definitions_are_named(tmp_path, edit, message):
    with pytest.raises(LeagueError, match=message):
        load_league(_write(tmp_path, edit))
