"""li2020 components: the flight side cannot see the truth; plant, reference, actuator and evaluation
against independent formulas; the evaluation hook and the infinity-norm metric of the closed loop."""

from __future__ import annotations

import dataclasses
import inspect
import typing

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components.actuators.step_faults import StepFaultActuator
from formation_ftc.components.controllers.li2020_adaptive import Li2020AdaptiveController
from formation_ftc.components.controllers.sir_ftc import SirFtcController
from formation_ftc.components.evaluations.formation_errors import FormationErrors
from formation_ftc.core.dynamics.relative_lvlh import relative_lvlh_rhs
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import ActuatorInputs, FlightInputs, TruthInputs
from formation_ftc.sim.metrics import Metric, finalize, init_accumulators, update_accumulators

TRUTH_FIELDS = {"state", "true_state", "fault", "faults", "disturbance", "force", "process_noise"}


def _loop(name, **ov):
    return make_loop(
        ftc.load_scenario(name, {"simulation.horizon": 1.0, "simulation.record_every": 1, **ov})
    )


def _other_truth(loop):
    """The same loop with different true faults, disturbance and masses (truth side only)."""
    act = loop.actuator
    if isinstance(act, StepFaultActuator):
        act = dataclasses.replace(
            act, alpha=act.alpha * 0.5, onset=act.onset * 0.0, bias=("3", "-2", "1")
        )
    else:
        act = dataclasses.replace(act, effectiveness=("0.3", "0.5", "0.7"), bias=("3", "-2", "1"))
    plant = dataclasses.replace(
        loop.plant, mass=loop.plant.mass * 1.7, disturbance_force=("5", "5*t", "-5")
    )
    return dataclasses.replace(loop, actuator=act, plant=plant)


@pytest.mark.parametrize(
    "name, cls",
    [
        ("li2020-thm1", Li2020AdaptiveController),
        ("li2020-thm2-delays", Li2020AdaptiveController),
        ("li2020-sirftc", SirFtcController),
    ],
)
def test_controller_cannot_see_the_truth(name, cls):
    """The controller's inputs are FlightInputs (no truth fields); with identical flight inputs its
    command is unchanged when the plant's masses / disturbance and the actuator's faults change,
    while the applied force does change."""
    hints = typing.get_type_hints(
        cls.output, globalns=vars(inspect.getmodule(cls)) | {"FlightInputs": FlightInputs}
    )
    assert hints["inputs"] is FlightInputs
    assert not TRUTH_FIELDS & set(FlightInputs._fields)
    loop = _loop(name)
    assert isinstance(loop.controller, cls)
    other = _other_truth(loop)
    k = jnp.asarray(3, dtype=jnp.int64)
    state = loop.initial_state()  # same true state, hence the same measurement, in both loops
    step = jax.jit(lambda lp, st: lp.step(k, st)[1])
    out_a, out_b = step(loop, state), step(other, state)
    np.testing.assert_array_equal(np.asarray(out_a["command"]), np.asarray(out_b["command"]))
    assert np.max(np.abs(np.asarray(out_a["applied"]) - np.asarray(out_b["applied"]))) > 1e-3


def test_plant_and_reference_equal_the_core_model():
    """RelativeLvlhPlant + KeplerianReference derivative = relative_lvlh_rhs (eqs. (1)-(4)) with the
    total force h + F."""
    loop = _loop("li2020-thm1")
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


def test_step_fault_actuator():
    alpha = jnp.asarray([[0.5, 1.0, 0.2]] * 2)
    onset = jnp.asarray([[1.0, 2.0, 3.0], [0.0, 5.0, 5.0]])
    act = StepFaultActuator(alpha=alpha, onset=onset, bias=("1", "0", "i"))
    u = jnp.ones((2, 3))
    F = act.apply(2.0, u, ActuatorInputs(act.exogenous(2.0), None))
    np.testing.assert_array_equal(np.asarray(F), [[1.5, 1.0, 2.0], [1.5, 1.0, 3.0]])


def test_formation_errors_and_inf_norm_metric_in_the_loop():
    """mu1 / mu2 / mu2_vc records equal the formulas applied to the recorded position error and
    position; max_control_force (infinity norm, every step) >= the max over the records."""
    scn = ftc.load_scenario(
        "li2020-sirftc", {"simulation.horizon": 2.0, "simulation.record_every": 10}
    )
    ds, m = ftc.api.simulate_with_metrics(scn)
    e1, rho = ds.position_error.values, ds.position.values
    np.testing.assert_allclose(
        ds.mu1.values, np.mean(np.linalg.norm(e1, axis=-1), axis=-1), rtol=1e-12
    )
    d = lambda i, j: np.linalg.norm(rho[:, i] - rho[:, j], axis=-1)  # noqa: E731
    np.testing.assert_allclose(
        ds.mu2.values, np.abs(2 * d(0, 1) - d(0, 2) - 2 * d(2, 3) + d(1, 3)), rtol=1e-9
    )
    vc = sum(
        np.linalg.norm(e1[:, i] - e1[:, j], axis=-1) for i in range(4) for j in range(i + 1, 4)
    )
    np.testing.assert_allclose(ds.mu2_vc.values, vc, rtol=1e-9)
    rec_max = float(np.max(np.abs(ds.command.values)))
    assert m["max_control_force"] >= rec_max and m["max_control_force"] < 1.2 * rec_max
    assert {s.name for s in FormationErrors().signals()} == {"mu1", "mu2", "mu2_vc"}


def test_metric_inf_norm():
    """norm_ord = 'inf': largest absolute component before the spacecraft and time reductions."""
    met = (Metric("peak", "u", "max", norm=True, norm_ord="inf", spacecraft="max"),)
    samples = [
        np.array([[1.0, -4.0, 2.0], [0.5, 0.5, 0.5]]),
        np.array([[3.0, 0.0, 0.0], [0.0, 0.0, -3.5]]),
    ]
    acc = init_accumulators(met, {"u": samples[0]})
    for k, u in enumerate(samples):
        acc = update_accumulators(met, acc, 0.1 * k, 0.1, {"u": jnp.asarray(u)})
    assert float(finalize(met, acc)[0]) == 4.0
    with pytest.raises(ValueError, match="norm_ord"):
        Metric("bad", "u", norm=True, norm_ord="1")


def test_metric_last_is_the_horizon_value():
    """'last' ignores the steps (accumulator unchanged) and takes the horizon sample, like 'final'."""
    met = (Metric("end", "u", "last"), Metric("fin", "u", "final"))
    acc = init_accumulators(met, {"u": jnp.asarray(0.0)})
    for k, u in enumerate((3.0, -1.0, 7.0)):
        acc = update_accumulators(met, acc, 0.1 * k, 0.1, {"u": jnp.asarray(u)})
    assert np.isnan(float(finalize(met, acc)[0])) and float(finalize(met, acc)[1]) == 7.0
    acc = update_accumulators(met, acc, 0.3, 0.1, {"u": jnp.asarray(2.5)}, is_final=True)
    assert [float(v) for v in finalize(met, acc)] == [2.5, 2.5]
