"""Every condition declares how it was computed (``Condition.basis``), and only an exact or verified
computation may say that it holds.

Truths: the rule itself (construction must fail), every built-in scenario's ``check`` output, and two
scenarios built to defeat sampling -- a delay that jumps (its rate is unbounded, the step-grid derivative
reads 0) and a disturbance spike narrower than the sample spacing (the samples read 0, the true peak
0.1 N exceeds the bound).
"""

from __future__ import annotations

import json

import pytest

import formation_ftc as ftc
from formation_ftc import api
from formation_ftc.cli import main
from formation_ftc.registry import BASES, Condition
from formation_ftc.report import html as rh


def _c(**kw):
    base = dict(name="c", reference="r", value="1", requirement="> 0", holds=True)
    return Condition(**{**base, **kw})


def test_basis_is_required_and_validated():
    with pytest.raises(TypeError):
        _c()  # no silent default
    with pytest.raises(ValueError, match="not one of"):
        _c(basis="exactish")
    for b in ("sampled", "heuristic"):
        with pytest.raises(ValueError, match="cannot prove"):
            _c(basis=b)
        assert _c(basis=b, holds=None).unproven and _c(basis=b, holds=False).holds is False
    with pytest.raises(ValueError, match="cannot be required"):
        _c(basis="informative")
    assert _c(basis="informative", required=False).holds
    for b in ("exact", "verified"):
        assert _c(basis=b).as_dict()["basis"] == b
    with pytest.raises(ValueError, match="holds must be"):
        _c(basis="exact", holds="yes")


@pytest.fixture(scope="module")
def all_checks():
    return {name: api.check(name) for name in api.list_scenarios()}


def test_every_builtin_condition_states_an_honest_basis(all_checks):
    assert len(all_checks) >= 20
    for name, conds in all_checks.items():
        for c in conds:
            assert c.basis in BASES, (name, c.name)
            if c.basis in ("sampled", "heuristic"):
                assert c.holds is not True, (name, c.name)
            if c.basis == "informative":
                assert not c.required, (name, c.name)
            assert c.basis in c.detail.lower(), (name, c.name, c.basis, c.detail)


def test_li2020_delay_conditions_are_verified(all_checks):
    conds = {c.name: c for c in all_checks["li2020-thm2-delays"]}
    for key in (
        "delays non-negative",
        "delay rate bound (used edges)",
        "delay rate bound (all printed delays)",
        "lambda_i > (rho - 1)/2 sum_j c_ij",
    ):
        assert conds[key].basis == "verified" and conds[key].holds is True, key
    assert "verified h <= 0.12" in conds["delay rate bound (used edges)"].value


def test_yang2013_disturbance_bounds_are_verified(all_checks):
    for name in ("yang2013-healthy", "yang2013-controller-fault"):
        conds = {c.name: c for c in all_checks[name]}
        for key in ("|d_i(t)| <= d_bar", "|iota_i(t)| <= iota_bar"):
            assert conds[key].basis == "verified" and conds[key].holds is True, (name, key)


def test_heuristic_and_sampled_passes_are_unproven(all_checks):
    rk4 = {c.name: c for c in all_checks["mehrabian-isolation"]}["RK4 step vs fastest rate"]
    assert rk4.basis == "heuristic" and rk4.holds is None
    bound8 = {c.name: c for c in all_checks["azizi2009-flfr"]}["error bound (8) at the FLFR weight"]
    assert bound8.basis == "sampled" and bound8.holds is None and bound8.required


def test_a_jumping_delay_falls_back_to_sampling():
    d = [list(r) for r in ftc.load_scenario("li2020-thm2-delays").section("network").delays]
    d[2][3] = "3 + 0.5*step(t - 100)"  # T34, a used edge: jumps by 0.5 s at t = 100 s
    conds = {
        c.name: c for c in api.check(ftc.load_scenario("li2020-thm2-delays", {"network.delays": d}))
    }
    rate = conds["delay rate bound (used edges)"]
    assert rate.basis == "sampled" and rate.holds is None and "unproven" in rate.detail
    assert conds["delays non-negative"].basis == "verified"


def test_a_spike_between_samples_is_not_certified(capsys):
    scn = ftc.load_scenario(
        "yang2013-healthy",
        {"plant.disturbance_force": ["0.1*window(t, 1000.0001, 1000.0002)", "0", "0"]},
    )
    c = {c.name: c for c in api.check(scn)}["|d_i(t)| <= d_bar"]
    assert c.basis == "sampled" and c.holds is None  # the old sampled check said "holds" here
    assert c.value.startswith("0 (sampled peak)")


def test_cli_and_html_show_basis_and_unproven(capsys, tmp_path):
    code = main(["check", "azizi2009-flfr"])
    out = capsys.readouterr().out
    assert code == 0  # exit codes unchanged: 1 only when a required condition is False
    line = next(ln for ln in out.splitlines() if ln.startswith("error bound (8)"))
    assert "unproven" in line and "sampled" in line
    assert "basis" in out.splitlines()[0]
    assert "1 required condition(s) unproven" in out
    assert main(["check", "azizi2009-flfr", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["required_unproven"] == 1 and all("basis" in c for c in data["conditions"])
    rows = [c.as_dict() for c in api.check("mehrabian-isolation")]
    checks = rh._checks({"checks": rows})  # what the report's checks table shows per row
    assert any(c["class"] == "holds-unproven" and c["holds"] == "unproven" for c in checks)
    assert sum(c["basis"] == "exact" for c in checks) >= 10
    old = {
        k: v for k, v in rows[0].items() if k != "basis"
    }  # a report.json written before the basis
    assert rh._checks({"checks": [old]})[0]["class"] == "holds-yes"
