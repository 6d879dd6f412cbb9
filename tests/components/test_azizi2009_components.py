"""azizi2009 components: the chain LLFR controller cannot see the truth; plant, sensors, actuator and
the chain tracking-error evaluation against independent formulas; the composition rejects a force law."""

from __future__ import annotations

import dataclasses
import inspect
import typing

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from formation_ftc.api import load_scenario
from formation_ftc.components.controllers.azizi2009_llfr import ChainLlfrController
from formation_ftc.components.controllers.pd import PdFormationController
from formation_ftc.components.evaluations.chain_errors import ChainTrackingError, ThresholdFlag
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import CompositionError, FlightInputs, SensorInputs, TruthInputs


def _loop(name="azizi2009-flfr", **ov):
    return make_loop(
        load_scenario(name, {"simulation.horizon": 2.0, "simulation.record_every": 100, **ov})
    )


def _other_truth(loop):
    """The same loop with different true faults and disturbance (truth side only)."""
    act = dataclasses.replace(
        loop.actuator, faulty_gain=loop.actuator.faulty_gain * 0.3, onset=jnp.asarray(0.7)
    )
    plant = dataclasses.replace(loop.plant, disturbance="1e-2*sin(t) + i")
    return dataclasses.replace(loop, actuator=act, plant=plant)


def test_controller_output_takes_flight_inputs_only():
    hints = typing.get_type_hints(ChainLlfrController.output)
    assert hints["inputs"] is FlightInputs
    assert list(inspect.signature(ChainLlfrController.output).parameters) == [
        "self",
        "t",
        "state",
        "inputs",
    ]
    assert not {"state", "true_state", "fault", "disturbance", "force"} & set(FlightInputs._fields)


def test_controller_blind_to_true_faults_and_disturbance():
    """Identical flight inputs -> identical command, whatever the plant's and actuator's truth leaves."""
    loop = _loop()
    other = _other_truth(loop)
    assert other.controller is loop.controller  # the truth change does not touch the flight side
    rng = np.random.default_rng(0)
    y = {
        "position": jnp.asarray(rng.normal(size=(3, 3))),
        "velocity": jnp.asarray(rng.normal(size=(3, 3))),
    }
    outs = []
    for lp in (loop, other):
        c = lp.controller
        for mode in (0, 1, 2):
            u, _, _ = c.output(
                jnp.asarray(1.3),
                c.initial_state(),
                FlightInputs(y, None, None, jnp.asarray(mode), None, None, None),
            )
            outs.append(np.asarray(u))
    for a, b in zip(outs[:3], outs[3:], strict=True):
        np.testing.assert_array_equal(a, b)
    assert not np.allclose(outs[0], outs[2])  # the mode does change the allocation
    # ... while the closed loops do differ (the truth change is real)
    r1 = jax.jit(lambda lp: lp.run())(loop)["records"]["tracking_error"]
    r2 = jax.jit(lambda lp: lp.run())(other)["records"]["tracking_error"]
    assert float(jnp.max(jnp.abs(r1 - r2))) > 1e-4


def test_controller_law_against_hand_formula():
    """Sec. II p_ij and eq. (3) for N = 3 on one axis, LLFR mode, checked by the constraint J(b_hat) u = p
    and the optimality condition sum alpha_i u_i / b_hat_i = 0 (E004-02)."""
    c = ChainLlfrController(
        lambda0=jnp.asarray(2.0),
        lambda1=jnp.asarray(3.0),
        alpha=jnp.asarray([1.0, 4.0, 2.0]),
        alpha_flfr=jnp.asarray(9.0),
        b_nominal=jnp.ones((3, 1)),
        b_hat=jnp.asarray([[1.0], [0.8], [1.1]]),
        side=jnp.asarray(100.0),
        omega=jnp.asarray(0.0),
        fault_index=1,
    )
    rd, _, _ = c.desired(0.0)  # omega = 0: the desired formation is at rest (xdd^d = 0)
    e, ed = np.array([0.1, -0.2]), np.array([0.01, 0.03])
    y = {"position": (rd[1:] - rd[:-1]) + e[:, None], "velocity": jnp.asarray(ed[:, None])}
    u, _, _ = c.output(
        0.0, c.initial_state(), FlightInputs(y, None, None, jnp.asarray(1), None, None, None)
    )
    u = np.asarray(u)[:, 0]
    p = -3.0 * ed - 2.0 * e
    b = np.array([1.0, 0.8, 1.1])
    np.testing.assert_allclose(
        [b[1] * u[1] - b[0] * u[0], b[2] * u[2] - b[1] * u[1]], p, rtol=1e-12
    )
    assert abs(np.sum(np.array([1.0, 4.0, 2.0]) * u / b)) < 1e-12


def test_plant_sensor_actuator_and_evaluation_against_formulas():
    loop = _loop(
        **{
            "actuator.onset": 1.0,
            "sensors.position_noise_std": 1e-3,
            "sensors.velocity_noise_std": 2e-3,
        }
    )
    p, s, a = loop.plant, loop.sensors, loop.actuator
    x = p.initial_state()
    u = jnp.ones((4, 3))
    # actuator: b = nominal before the onset, faulty (0.8 on satellite 2, x) from it on
    for t, b2x in ((0.999, 1.0), (1.0, 0.8)):
        app = a.apply(t, u, type("I", (), {"exogenous": a.exogenous(jnp.asarray(t))})())
        assert float(app[1, 0]) == pytest.approx(b2x) and float(app[0, 0]) == 1.0
    # plant: exact step of x'' = a + d with d = 1e-5 cos(0.01 t + i)
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
    # sensors: chain differences plus the noise drawn for the step (position and velocity streams)
    key = jax.random.PRNGKey(3)
    noise = s.noise(key)
    y = s.measure(0.0, x, SensorInputs(noise, None))
    np.testing.assert_allclose(
        y["position"], np.diff(np.asarray(x["r"]), axis=0) + noise["position"], atol=1e-12
    )
    k_r, k_v = jax.random.split(key)
    np.testing.assert_allclose(
        noise["velocity"], 2e-3 * np.asarray(jax.random.normal(k_v, (3, 3))), rtol=1e-15
    )
    # evaluation: (x_j - x_i) - (x_j^d - x_i^d)
    pos, des = np.arange(12.0).reshape(4, 3) ** 2, np.arange(12.0).reshape(4, 3)
    te = ChainTrackingError().outputs(
        {"position": jnp.asarray(pos), "desired_position": jnp.asarray(des)}
    )
    np.testing.assert_allclose(te["tracking_error"], (pos[1:] - pos[:-1]) - (des[1:] - des[:-1]))
    flag = ThresholdFlag(name="f", source="s", threshold=jnp.asarray(0.25))
    assert [bool(flag.outputs({"s": jnp.asarray(v)})["f"]) for v in (0.2, 0.25, 0.3)] == [
        False,
        True,
        True,
    ]


def test_force_law_is_rejected_on_the_acceleration_plant():
    loop = _loop()
    pd = PdFormationController(
        count=4, kp=jnp.asarray(1.0), kd=jnp.asarray(1.0), nominal_mass=jnp.ones(4)
    )
    with pytest.raises(CompositionError, match="force"):
        dataclasses.replace(loop, controller=pd).validate()
