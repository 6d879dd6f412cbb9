"""Gui2022's output-feedback laws (``gui2022-lof2tc``, ``gui2022-cof2tc``; free drift in ``gui2022-ilo``)
read flight inputs only: with identical flight inputs their output is unchanged when every truth-side
leaf changes; LOF2TC's law (30)-(32) against its formulas written out in numpy."""

import dataclasses
import inspect
import typing

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components.controllers.gui2022_cof2tc import ConventionalOutputFeedbackController
from formation_ftc.components.controllers.gui2022_lof2tc import (
    LearningOutputFeedbackController,
    lof2tc_law,
)
from formation_ftc.components.controllers.none import FreeDrift
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import FlightInputs

#: scenario of each law -> its controller component
CONTROLLERS = {
    "gui2022-ilo": FreeDrift,
    "gui2022-lof2tc": LearningOutputFeedbackController,
    "gui2022-cof2tc": ConventionalOutputFeedbackController,
}


def _loop(name):
    return make_loop(
        ftc.load_scenario(name, {"simulation.horizon": 0.01, "simulation.record_every": 1})
    )


def _with_other_truth(loop):
    """The same loop with every truth-side leaf changed: disturbance, fault profile and onsets."""
    act = loop.actuator
    act2 = dataclasses.replace(
        act,
        onset=jnp.zeros_like(act.onset),
        magnitude=act.magnitude + 0.3,
        amplitude=act.amplitude + 0.1,
        omega=act.omega + 1.0,
    )
    plant2 = dataclasses.replace(
        loop.plant, disturbance_amplitude=loop.plant.disturbance_amplitude * 7 + 1e-3
    )
    return dataclasses.replace(loop, plant=plant2, actuator=act2)


@pytest.mark.parametrize("name", sorted(CONTROLLERS))
def test_controller_reads_flight_inputs_only(name):
    loop = _loop(name)
    ctl = loop.controller
    assert type(ctl) is CONTROLLERS[name]
    hints = typing.get_type_hints(type(ctl).output)
    assert hints["inputs"] is FlightInputs
    assert list(inspect.signature(type(ctl).output).parameters) == ["self", "t", "state", "inputs"]
    assert not {"force", "process_noise"} & set(
        FlightInputs._fields
    )  # no truth channel in the type
    other = _with_other_truth(loop)
    # the truth really differs at t = 0 (faults active from 0 in `other`) ...
    t0 = jnp.asarray(0.0)
    f_a = loop.actuator.exogenous(t0)["F"]
    f_b = other.actuator.exogenous(t0)["F"]
    assert not np.allclose(f_a, f_b)
    assert not np.allclose(loop.plant.exogenous(t0)["d"], other.plant.exogenous(t0)["d"])
    # ... but given identical flight inputs the controller's output is identical (it is the same component)
    rng = np.random.default_rng(1)
    flight = FlightInputs(
        measurement=jnp.asarray(rng.normal(size=(1, 6))),
        received=None,
        estimate={
            "fault": jnp.asarray(rng.normal(size=(1, 3))),
            "state": None,
            "output_error": None,
        },
        decision=None,
        exogenous=ctl.exogenous(t0),
        reference=None,
        step=None,
    )
    out_a = ctl.output(t0, ctl.initial_state(), flight)
    out_b = other.controller.output(t0, other.controller.initial_state(), flight)
    jax.tree_util.tree_map(np.testing.assert_array_equal, out_a, out_b)
    # and inside the closed loop, the first command (same measurement y_0) is unchanged by the truth
    sig_a = jax.jit(
        lambda lp: lp.prepared().observe(jnp.asarray(0), lp.prepared().initial_state())
    )(loop)
    sig_b = jax.jit(
        lambda lp: lp.prepared().observe(jnp.asarray(0), lp.prepared().initial_state())
    )(other)
    np.testing.assert_array_equal(sig_a["command"], sig_b["command"])
    assert not np.allclose(sig_a["applied"], sig_b["applied"])  # the truth side did see the change


def test_lof2tc_law_against_its_formulas():
    """(31) pi = G1 pi_past + G2 |K e|^2, (32) v = G3 v_past + G4 K e, (30) u = pi K e - B^+E v - B^+H F."""
    rng = np.random.default_rng(7)
    e_y, F = rng.normal(size=(2, 6)), rng.normal(size=(2, 3))
    pi_past, v_past = rng.normal(size=2), rng.normal(size=(2, 3))
    K, BpE, BpH = rng.normal(size=(3, 6)), rng.normal(size=(3, 3)), rng.normal(size=(3, 3))
    G3 = np.array([0.9, 0.8, 0.7])
    u, pi, v = lof2tc_law(e_y, F, pi_past, v_past, K, 0.99, 0.5, G3, -0.9, BpE, BpH)
    for i in range(2):
        Ke = K @ e_y[i]
        pi_i = 0.99 * pi_past[i] + 0.5 * float(Ke @ Ke)
        v_i = G3 * v_past[i] - 0.9 * Ke
        np.testing.assert_allclose(pi[i], pi_i, rtol=1e-13)
        np.testing.assert_allclose(v[i], v_i, rtol=1e-13)
        np.testing.assert_allclose(u[i], pi_i * Ke - BpE @ v_i - BpH @ F[i], rtol=1e-12, atol=1e-14)
