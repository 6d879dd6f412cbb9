"""Plant ``double-integrator``: the exact held-acceleration step against its closed form."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from formation_ftc.api import load_scenario
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import TruthInputs


def test_exact_step_against_the_closed_form():
    """x'' = a + d with d = 1e-5 cos(0.01 t + i) (azizi2009-flfr's disturbance) held over the step."""
    loop = make_loop(load_scenario("azizi2009-flfr", {"simulation.horizon": 2.0}))
    p = loop.plant
    x = p.initial_state()
    t, dt = 0.3, 1e-3
    d = 1e-5 * np.cos(0.01 * t + np.arange(1, 5))[:, None] * np.ones(3)
    acc = np.full((4, 3), 0.5)
    new = p.exact_step(
        t, x, TruthInputs(jnp.asarray(acc), p.exogenous(jnp.asarray(t)), None, None), dt
    )
    np.testing.assert_allclose(
        new["r"], x["r"] + x["v"] * dt + 0.5 * (acc + d) * dt**2, rtol=0, atol=1e-13
    )
    np.testing.assert_allclose(new["v"], x["v"] + (acc + d) * dt, rtol=0, atol=1e-15)


def test_axes_and_integration_are_builder_inputs():
    """``axes`` keeps the first axes of the stated rows; ``integration = "rk4"`` is the RK4 plant (and
    then provides the RK stages a continuous law needs)."""
    loop = make_loop(
        load_scenario(
            "azizi2009-flfr",
            {"simulation.horizon": 2.0, "plant.axes": 2, "plant.integration": "rk4"},
        )
    )
    raw = load_scenario("azizi2009-flfr").section("plant")
    np.testing.assert_array_equal(
        loop.plant.initial_position, np.asarray(raw.initial_position)[:, :2]
    )
    assert loop.plant.integration == "rk4" and "stage-evaluation" in loop.plant.provides()
