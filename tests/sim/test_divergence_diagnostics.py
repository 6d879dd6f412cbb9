"""Divergence diagnostics name the state variable that left its admissible set, not an accumulator
(integrated delta-v, effort) that merely follows it -- whatever the leaves' names or order."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from formation_ftc.sim.engine import _accumulators, diagnose_divergence


def _step(k, s):
    # x doubles with an exploding gain after step 3; "a_dv" and "b_effort" integrate |u| (u = -g x)
    g = jnp.where(k >= 3, 1e308, 0.5)
    u = -g * s["x"]
    return {
        "a_dv": s["a_dv"] + jnp.abs(u),
        "b_effort": s["b_effort"] + u**2,
        "x": s["x"] + u * 0 + 2.0 * s["x"],
        "z_mode": s["z_mode"],
    }


def _state():
    return {
        "a_dv": jnp.zeros(2),
        "b_effort": jnp.zeros(2),
        "x": jnp.array([1e-300, 1e300]),
        "z_mode": jnp.asarray(1.0),
    }


def test_accumulators_are_found_from_the_jaxpr():
    acc = _accumulators(_step, jnp.asarray(0, dtype=jnp.int64), _state())
    assert acc == {
        0,
        1,
        3,
    }  # a_dv, b_effort and the constant mode: nothing else reads them; x is read


def test_names_the_state_not_the_accumulator_that_sorts_first():
    info = diagnose_divergence(_step, _state(), 0, 0.0, max_steps=10, dt=0.5)
    assert info.variable == "x" and info.index == (1,)
    # b_effort = u**2 overflows already at step 0; x itself leaves the finite set later, and that
    # step (found here by plain stepping) is the one reported
    s, k = _state(), 0
    assert not np.isfinite(np.asarray(_step(0, s)["b_effort"])).all()
    while np.isfinite(np.asarray(_step(k, s)["x"])).all():
        s, k = _step(k, s), k + 1
    assert k > 0 and info.step == k and info.time == 0.5 * k


def test_only_accumulators_non_finite_follows_to_the_cause():
    # the control overflows into the accumulator at step 2; the state x follows at step 4
    def step(k, s):
        u = jnp.where(k >= 2, jnp.inf, 1.0) * (1.0 + jnp.abs(s["x"]))  # the control reads the state
        return {"dv": s["dv"] + jnp.abs(u), "x": s["x"] + jnp.where(k >= 4, jnp.inf, 1.0)}

    s0 = {"dv": jnp.zeros(()), "x": jnp.zeros(())}
    info = diagnose_divergence(step, s0, 0, 0.0, max_steps=3, dt=1.0)
    assert info.variable == "x" and info.step == 4
    # when the state never follows, the accumulator is named (never "<unknown>")
    info = diagnose_divergence(
        lambda k, s: {"dv": s["dv"] + jnp.where(k >= 1, jnp.inf, 1.0), "x": s["x"]},
        s0,
        0,
        0.0,
        max_steps=3,
        dt=1.0,
    )
    assert info.variable == "dv" and info.step == 1
