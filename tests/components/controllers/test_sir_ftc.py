"""Controller ``sir-ftc``: its kernels against the per-agent formulas of the SIR-FTC baseline (Li2020
Sec. IV-D) and the law's blindness to the truth."""

from __future__ import annotations

import dataclasses
import inspect
import typing

import jax
import jax.numpy as jnp
import numpy as np

import formation_ftc as ftc
from formation_ftc.components.controllers.sir_ftc import (
    SirFtcController,
    sir_epsilon,
    sir_ftc_control,
    sir_ftc_rate,
)
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import FlightInputs

rng = np.random.default_rng(3)


def test_sir_ftc_formula():
    s = rng.normal(size=(4, 3))
    b = rng.uniform(0, 10, 4)
    eps = sir_epsilon(1.0, 1.0)
    assert eps == 0.5
    f = np.asarray(sir_ftc_control(s, b, 20.0, 1.0, eps))
    bd = np.asarray(sir_ftc_rate(s, b, 1.0, eps, 1.0, 10.0))
    for i in range(4):
        n = np.linalg.norm(s[i])
        assert np.allclose(f[i], -(20 + b[i] / (n + eps)) * s[i])
        assert np.isclose(bd[i], -b[i] + 10 * n**2 / (n + eps))


def test_controller_cannot_see_the_truth():
    """The controller's inputs are FlightInputs; with identical flight inputs its command is unchanged
    when the plant's masses / disturbance and the actuator's faults change, while the applied force
    does change."""
    hints = typing.get_type_hints(
        SirFtcController.output,
        globalns=vars(inspect.getmodule(SirFtcController)) | {"FlightInputs": FlightInputs},
    )
    assert hints["inputs"] is FlightInputs
    loop = make_loop(
        ftc.load_scenario(
            "li2020-sirftc", {"simulation.horizon": 1.0, "simulation.record_every": 1}
        )
    )
    assert isinstance(loop.controller, SirFtcController)
    act = dataclasses.replace(
        loop.actuator, effectiveness=("0.3", "0.5", "0.7"), bias=("3", "-2", "1")
    )
    plant = dataclasses.replace(
        loop.plant, mass=loop.plant.mass * 1.7, disturbance_force=("5", "5*t", "-5")
    )
    other = dataclasses.replace(loop, actuator=act, plant=plant)
    k = jnp.asarray(3, dtype=jnp.int64)
    state = loop.initial_state()
    step = jax.jit(lambda lp, st: lp.step(k, st)[1])
    out_a, out_b = step(loop, state), step(other, state)
    np.testing.assert_array_equal(np.asarray(out_a["command"]), np.asarray(out_b["command"]))
    assert np.max(np.abs(np.asarray(out_a["applied"]) - np.asarray(out_b["applied"]))) > 1e-3
