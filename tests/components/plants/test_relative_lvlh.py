"""Plant ``relative-lvlh`` with reference ``keplerian``: the derivative against the core model of Li2020
eqs. (1)-(4); the plant is refused without a reference orbit."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.config.loader import ScenarioError
from formation_ftc.core.dynamics.relative_lvlh import relative_lvlh_rhs
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import TruthInputs


def test_plant_and_reference_equal_the_core_model():
    """RelativeLvlhPlant + KeplerianReference derivative = relative_lvlh_rhs (eqs. (1)-(4)) with the
    total force h + F."""
    loop = make_loop(
        ftc.load_scenario("li2020-thm1", {"simulation.horizon": 1.0, "simulation.record_every": 1})
    )
    rng = np.random.default_rng(0)
    q = jnp.asarray(rng.normal(size=(4, 6)) * [100, 100, 100, 0.1, 0.1, 0.1])
    theta = 0.7
    ref = loop.reference.values(jnp.asarray(theta))
    F = jnp.asarray(rng.normal(size=(4, 3)))
    exo = loop.plant.exogenous(12.5)
    dq = loop.plant.derivative(12.5, {"q": q}, TruthInputs(F, exo, ref, None))["q"]
    o = loop.reference
    want = relative_lvlh_rhs(
        0.0,
        {"theta": theta, "rho": q[:, :3], "v": q[:, 3:]},
        exo["h"] + F,
        loop.plant.mass,
        o.semi_latus_rectum,
        o.eccentricity,
        o.mu,
    )
    np.testing.assert_allclose(np.asarray(dq[:, :3]), np.asarray(want["rho"]), rtol=1e-14)
    np.testing.assert_allclose(np.asarray(dq[:, 3:]), np.asarray(want["v"]), rtol=1e-12, atol=1e-15)
    assert float(loop.reference.rate(jnp.asarray(theta))) == pytest.approx(
        float(want["theta"]), rel=1e-15
    )
    # the reference's semi-latus rectum is p = a (1 - e^2) of the [reference] section
    sec = ftc.load_scenario("li2020-thm1").section("reference")
    assert float(o.semi_latus_rectum) == sec.semi_major_axis * (1.0 - sec.eccentricity**2)


def test_the_plant_is_refused_without_a_reference_orbit():
    raw = {
        "scenario": {"name": "no-ref", "method": "composed"},
        "simulation": {"horizon": 1.0, "dt": 0.1},
        "plant": {"type": "relative-lvlh", "mass": [10.0], "initial_position": [[1.0, 0.0, 0.0]]},
        "controller": {"type": "none"},
    }
    with pytest.raises(
        ScenarioError,
        match=r"plant relative-lvlh needs a reference orbit known on board to integrate the "
        r"relative motion about it.*provided by: a \[reference\] section",
    ):
        ftc.load_scenario(raw)
    ftc.load_scenario({**raw, "reference": {"type": "keplerian", "semi_major_axis": 7000e3}})
