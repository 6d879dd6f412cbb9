"""The iterative learning observer (``iterative-learning-observer``) reads flight inputs only; its force
loop (AccelerationModelEstimator: the force command per unit nominal mass) and the PerUnitMass
evaluation against numpy formulas written out here."""

from __future__ import annotations

import dataclasses
import inspect
import typing

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components.estimators._acceleration_model import AccelerationModelEstimator
from formation_ftc.components.estimators.iterative_learning_observer import (
    IterativeLearningObserver,
)
from formation_ftc.components.evaluations._per_unit_mass import PerUnitMass
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import CompositionError, FlightInputs


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


def _ilo(n_sc: int, rng) -> IterativeLearningObserver:
    return IterativeLearningObserver(
        count=n_sc,
        mean_motion=np.float64(1.1e-3),
        L1=rng.normal(size=(6, 6)),
        L2=rng.normal(size=(3, 6)),
        Q1=np.array([0.9, 0.8, 0.7]),
        Q2=np.float64(0.5),
        gamma=np.float64(0.01),
        initial_estimate=rng.normal(size=(n_sc, 6)),
        fault_prehistory=rng.normal(size=(n_sc, 3)),
        learning_steps=1,
        sign_term=True,
        mean_steps=1,
    )


def test_time_update_receives_the_force_per_nominal_mass():
    rng = np.random.default_rng(3)
    ilo = _ilo(2, rng)
    mass = np.array([100.0, 120.0])
    est = AccelerationModelEstimator(inner=ilo, nominal_mass=mass)
    y = rng.normal(size=(2, 6))
    state0 = est.initial_state(y)
    state, estimate = est.update(
        0.0, state0, FlightInputs(jnp.asarray(y), None, None, None, None, None, None)
    )
    force = rng.normal(size=(2, 3)) * 50.0
    dt = 0.001
    got = np.asarray(est.predict(0.0, state, jnp.asarray(force), dt)["q_hat"])
    # independent: forward Euler of the CW observer (5) with u = f / m_nom, H = B = [0; I3]
    n = 1.1e-3
    A = np.zeros((6, 6))
    A[:3, 3:] = np.eye(3)
    A[3, 0], A[3, 4], A[4, 3], A[5, 2] = 3 * n**2, 2 * n, -2 * n, -(n**2)
    q_hat = np.asarray(ilo.initial_estimate)
    e_y = y - q_hat
    F_hat = (
        np.array([0.9, 0.8, 0.7]) * np.asarray(ilo.fault_prehistory)
        + 0.5 * e_y @ np.asarray(ilo.L2).T
    )
    np.testing.assert_allclose(np.asarray(estimate["fault"]), F_hat, rtol=1e-12, atol=1e-14)
    u = force / mass[:, None]
    B = np.vstack([np.zeros((3, 3)), np.eye(3)])
    rate = q_hat @ A.T + (u + F_hat) @ B.T + e_y @ np.asarray(ilo.L1).T + 0.01 * np.sign(e_y)
    np.testing.assert_allclose(got, q_hat + dt * rate, rtol=1e-12, atol=1e-12)
    # everything else is the inner observer's
    assert est.signals() == ilo.signals() and est.count == 2


def test_bad_nominal_masses_are_refused_naming_the_estimator():
    ilo = _ilo(2, np.random.default_rng(0))
    for bad in (np.array([100.0]), np.array([100.0, 0.0]), np.array([100.0, np.nan])):
        with pytest.raises(CompositionError, match="IterativeLearningObserver"):
            AccelerationModelEstimator(inner=ilo, nominal_mass=bad)


def test_per_unit_mass_divides_each_spacecraft_by_its_mass():
    f = np.arange(12.0).reshape(4, 3) - 5.0
    m = np.array([100.0, 120.0, 115.0, 108.0])
    out = PerUnitMass("a", "f", mass=m).outputs({"f": jnp.asarray(f)})["a"]
    np.testing.assert_allclose(
        np.asarray(out), np.stack([f[i] / m[i] for i in range(4)]), rtol=1e-15
    )


def test_a_navigation_filter_needs_a_force_driven_plant():
    nav = {"semi_major_axis": 7000e3, "position_noise_std": 0.1, "velocity_noise_std": 1e-3}
    with pytest.raises(ValueError, match="estimator.navigation: .* driven by acceleration"):
        ftc.load_scenario("gui2022-lof2tc", {"estimator.navigation": nav})
