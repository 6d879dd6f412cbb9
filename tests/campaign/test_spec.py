"""Campaign file validation: every bad input is an error naming the field, raised before any run."""

from __future__ import annotations

import pytest

from formation_ftc.campaign import CampaignError, load_campaign, make_plan, run_campaign
from formation_ftc.campaign.spec import (
    Choice,
    Grid,
    Integer,
    LogUniform,
    Normal,
    Uniform,
    parse_sampler,
)


@pytest.mark.parametrize(
    "spec, message",
    [
        ({"dist": "uniform", "low": 3.0, "high": 1.0}, "uniform needs low < high"),
        ({"dist": "uniform", "low": 1.0}, "needs high"),
        ({"dist": "normal", "mean": 1.0, "std": 0.0}, "std > 0"),
        ({"dist": "normal", "mean": 1.0, "std": 1.0, "low": 2.0, "high": 1.0}, "low < high"),
        ({"dist": "loguniform", "low": 0.0, "high": 1.0}, "0 < low < high"),
        ({"dist": "integer", "low": 1.5, "high": 3}, "must be an integer"),
        ({"dist": "integer", "low": 4, "high": 3}, "low <= high"),
        ({"dist": "uniform", "low": float("nan"), "high": 1.0}, "finite"),
        ({"dist": "beta", "a": 1}, "unknown dist 'beta'"),
        ({"dist": "uniform", "low": 0.0, "high": 1.0, "mean": 2.0}, "unknown key"),
        ({"grid": []}, "non-empty list"),
        ({"grid": [1], "choice": [2]}, "exactly one of"),
        ({"choice": [1, 2], "weights": [1.0]}, "weights must be a list of 2"),
        ({"choice": [1, 2], "weights": [-1.0, 0.5]}, ">= 0"),
        (5.0, "expected a table"),
    ],
)
def test_invalid_distribution_parameters(spec, message):
    with pytest.raises(CampaignError, match=message) as exc:
        parse_sampler("controller.kp", spec)
    assert "sample.controller.kp" in str(exc.value)


def test_sampler_types():
    assert isinstance(parse_sampler("a", {"dist": "uniform", "low": 0, "high": 1}), Uniform)
    assert isinstance(parse_sampler("a", {"dist": "normal", "mean": 0, "std": 1}), Normal)
    assert isinstance(parse_sampler("a", {"dist": "loguniform", "low": 1, "high": 2}), LogUniform)
    assert isinstance(parse_sampler("a", {"dist": "integer", "low": 1, "high": 2}), Integer)
    assert isinstance(parse_sampler("a", {"choice": ["x", "y"]}), Choice)
    g = parse_sampler("a", {"grid": [1, 2.5]})
    assert isinstance(g, Grid) and g.kind == "grid" and g.numeric


def test_campaign_file_errors_name_the_field(tmp_path, tiny, write_campaign):
    raw = tiny()
    raw["campaign"]["runs"] = 0
    with pytest.raises(CampaignError, match=r"field campaign.runs"):
        load_campaign(write_campaign(tmp_path / "c.toml", raw))
    raw = tiny()
    raw["campaign"]["colour"] = "red"
    with pytest.raises(CampaignError, match=r"field campaign.colour: unknown field"):
        load_campaign(raw)
    raw = tiny()
    raw["sample"]["controller.kp"] = {"dist": "uniform", "low": 2.0, "high": 1.0}
    with pytest.raises(CampaignError, match=r"sample.controller.kp: uniform needs low < high"):
        load_campaign(raw)
    raw = tiny()
    raw["sample"]["simulation.seed"] = {"grid": [1, 2]}
    with pytest.raises(CampaignError, match="simulation.seed"):
        load_campaign(raw)
    with pytest.raises(CampaignError, match="unknown campaign 'no-such-campaign'"):
        load_campaign("no-such-campaign")


def test_nested_tables_equal_quoted_dotted_keys(tiny):
    a = tiny()
    b = tiny()
    b["sample"] = {
        "controller": {"kp": a["sample"]["controller.kp"], "kd": a["sample"]["controller.kd"]},
        "plant": {"mass": {"0": a["sample"]["plant.mass.0"]}},
    }
    b["overrides"] = {"simulation": {"horizon": 20.0}}
    sa, _ = load_campaign(a)
    sb, _ = load_campaign(b)
    assert sa.sample == sb.sample and sa.overrides == sb.overrides
    assert make_plan(a).hash == make_plan(b).hash


@pytest.mark.parametrize(
    "path, where",
    [
        ("controller.kpp", "at controller it has fields: type, mode, kp"),
        ("plant.mass.7", "a list of 4 item(s)"),
        ("nosuch.section", "<top level>"),
    ],
)
def test_bad_dotted_path_is_refused_before_any_run(tmp_path, path, where, tiny):
    raw = tiny()
    raw["sample"][path] = {"dist": "uniform", "low": 1.0, "high": 2.0}
    out = tmp_path / "out"
    with pytest.raises(CampaignError, match="dotted path does not exist") as exc:
        run_campaign(raw, out)
    assert f"sample.{path}" in str(exc.value) and where in str(exc.value)
    assert not out.exists()  # nothing was run or written


def test_bound_outside_allowed_range_is_refused_before_any_run(tmp_path, tiny):
    raw = tiny()
    raw["sample"]["controller.kp"] = {
        "dist": "uniform",
        "low": -1.0,
        "high": 2.0,
    }  # schema: kp >= 0
    out = tmp_path / "out"
    with pytest.raises(CampaignError, match=r"sample.controller.kp: value -1.0 .* outside") as exc:
        run_campaign(raw, out)
    assert "controller.kp" in str(exc.value).split("outside", 1)[1]  # the schema's message names it
    assert not out.exists()


def test_unbounded_sample_outside_range_is_caught_for_every_run_before_any_run(tmp_path, tiny):
    raw = tiny()
    # a normal mass with mean 5 kg and std 20 kg gives negative masses in some runs (schema: > 0)
    raw["sample"]["plant.mass.0"] = {"dist": "normal", "mean": 5.0, "std": 20.0}
    raw["campaign"]["runs"] = 20
    out = tmp_path / "out"
    with pytest.raises(
        CampaignError, match=r"nothing was run[\s\S]*plant: mass: at least one spacecraft"
    ):
        run_campaign(raw, out)
    assert not out.exists()


def test_unknown_metric_is_refused_before_any_run(tmp_path, tiny):
    raw = tiny(metrics=["max_position_error", "no_such_metric"])
    out = tmp_path / "out"
    with pytest.raises(CampaignError, match=r"no_such_metric.*available: max_position_error"):
        run_campaign(raw, out)
    assert not out.exists()


def test_trace_run_ids_must_exist(tiny):
    raw = tiny()
    raw["traces"]["runs"] = [0, 99]
    with pytest.raises(CampaignError, match=r"traces.runs: run id\(s\) \[99\]"):
        make_plan(raw)
