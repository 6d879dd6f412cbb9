"""gui2022 components: the output-feedback controllers and the ILO cannot see the truth; the exact CW
plant, the thruster-fault actuator and the evaluation signals against independent formulas."""

import dataclasses
import inspect
import typing

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components.actuators.thruster_bias import ThrusterBiasFaultActuator
from formation_ftc.components.controllers.none import FreeDrift
from formation_ftc.components.controllers.output_feedback import (
    ConventionalOutputFeedbackController,
    LearningOutputFeedbackController,
)
from formation_ftc.components.estimators.iterative_learning_observer import (
    IterativeLearningObserver,
)
from formation_ftc.components.evaluations.signal_arithmetic import PartNorm, SignalSum
from formation_ftc.components.plants.clohessy_wiltshire_zoh import ZohClohessyWiltshirePlant
from formation_ftc.core.dynamics.cw import cw_matrices
from formation_ftc.core.integrators import zoh_discretize
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import ActuatorInputs, FlightInputs, TruthInputs

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


def test_ilo_reads_flight_inputs_only():
    loop = _loop("gui2022-lof2tc")
    est = loop.estimator
    assert isinstance(est, IterativeLearningObserver)
    assert typing.get_type_hints(type(est).update)["inputs"] is FlightInputs
    assert list(inspect.signature(type(est).predict).parameters) == [
        "self",
        "t",
        "state",
        "command",
        "dt",
    ]
    other = _with_other_truth(loop)
    y = jnp.asarray(np.random.default_rng(2).normal(size=(1, 6)))
    flight = FlightInputs(y, None, None, None, None, None, None)
    s_a, e_a = est.update(0.0, est.initial_state(y), flight)
    s_b, e_b = other.estimator.update(0.0, other.estimator.initial_state(y), flight)
    jax.tree_util.tree_map(np.testing.assert_array_equal, (s_a, e_a), (s_b, e_b))


def test_exact_cw_step_matches_scipy_zoh():
    n, dt = 0.0011, 0.5
    rng = np.random.default_rng(3)
    q0, u = rng.normal(size=(2, 6)) * [100, 100, 100, 0.1, 0.1, 0.1], rng.normal(size=(2, 3)) * 1e-3
    plant = ZohClohessyWiltshirePlant(
        mean_motion=jnp.asarray(n),
        initial_state_lvlh=jnp.asarray(q0),
        disturbance_amplitude=jnp.asarray(2e-4),
    )
    t = 123.0
    d = plant.exogenous(jnp.asarray(t))["d"]
    nt = n * t
    d_ref = 2e-4 * np.array([1 - 1.5 * np.sin(nt), 0.5 * np.sin(2 * nt), np.sin(nt)])
    np.testing.assert_allclose(d, np.broadcast_to(d_ref, (2, 3)), rtol=1e-13, atol=1e-20)
    got = plant.prepare(dt).exact_step(
        t, {"q": jnp.asarray(q0)}, TruthInputs(jnp.asarray(u), {"d": d}, None, None), dt
    )["q"]
    A, B = cw_matrices(n)
    Ad, Bd = zoh_discretize(A, B, dt)
    want = q0 @ Ad.T + (u + d_ref) @ Bd.T
    np.testing.assert_allclose(np.asarray(got), want, rtol=1e-12, atol=1e-12)
    # without prepare() the step computes the discretisation itself
    got2 = plant.exact_step(
        t, {"q": jnp.asarray(q0)}, TruthInputs(jnp.asarray(u), {"d": d}, None, None), dt
    )
    np.testing.assert_allclose(np.asarray(got2["q"]), want, rtol=1e-12, atol=1e-12)


def test_thruster_bias_profile():
    act = ThrusterBiasFaultActuator(
        count=1,
        onset=jnp.asarray([[1.0, 2.0, 3.0]]),
        magnitude=jnp.asarray([[0.5, -0.1, 0.0]]),
        amplitude=jnp.asarray([[0.0, 0.0, 0.25]]),
        omega=jnp.asarray([[0.0, 0.0, 0.05]]),
        phase=jnp.asarray([[0.0, 0.0, np.pi / 4]]),
        decay_amplitude=jnp.asarray([[0.0, 0.0, -0.2]]),
        decay_rate=jnp.asarray([[0.0, 0.0, 0.1]]),
        decay_origin=jnp.asarray([[0.0, 0.0, 3.0]]),
    )
    for t in (0.5, 1.0, 2.5, 3.0, 10.0):
        F = np.asarray(act.exogenous(jnp.asarray(t))["F"])[0]
        want = [
            0.5 * (t >= 1),
            -0.1 * (t >= 2),
            (0.25 * np.sin(0.05 * t + np.pi / 4) - 0.2 * np.exp(-0.1 * (t - 3.0))) * (t >= 3),
        ]
        np.testing.assert_allclose(F, want, rtol=1e-14, atol=1e-16)
        u = np.array([[1.0, 2.0, 3.0]])
        applied = act.apply(t, jnp.asarray(u), ActuatorInputs(act.exogenous(jnp.asarray(t)), None))
        np.testing.assert_allclose(np.asarray(applied)[0], u[0] + want, rtol=1e-14)


def test_signal_sum_and_part_norm():
    rng = np.random.default_rng(4)
    a, b, c = (rng.normal(size=(2, 6)) for _ in range(3))
    s = SignalSum("h", (("+", "a"), ("-", "b"), ("+", "c"))).outputs({"a": a, "b": b, "c": c})["h"]
    np.testing.assert_allclose(s, a - b + c, rtol=1e-15)
    neg = SignalSum("h", (("-", "a"),)).outputs({"a": a})["h"]
    np.testing.assert_array_equal(neg, -a)
    pn = PartNorm("p", "a", 3, 6).outputs({"a": a})["p"]
    np.testing.assert_allclose(pn, np.linalg.norm(a[:, 3:], axis=1), rtol=1e-15)
    with pytest.raises(ValueError, match="sign"):
        SignalSum("h", (("*", "a"),))
