"""Controller ``azizi2009-llfr``: the chain LLFR law cannot see the truth, its law against a hand
formula (Sec. II, eq. (3)), the chain outputs formed on board from the relative state equal the chain
measurement, and the loop refuses a force law on the acceleration plant."""

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
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import CompositionError, FlightInputs


def _loop(name="azizi2009-flfr", **ov):
    return make_loop(
        load_scenario(name, {"simulation.horizon": 2.0, "simulation.record_every": 100, **ov})
    )


def _other_truth(loop):
    """The same loop with different true faults and disturbance (truth side only)."""
    act = dataclasses.replace(
        loop.actuator, faulty_gain=loop.actuator.faulty_gain * 0.3, onset=jnp.asarray(0.7)
    )
    plant = dataclasses.replace(loop.plant, disturbance_acceleration="1e-2*sin(t) + i")
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


def _law(**kw):
    return ChainLlfrController(
        lambda0=jnp.asarray(2.0),
        lambda1=jnp.asarray(3.0),
        alpha=jnp.asarray([1.0, 4.0, 2.0]),
        alpha_flfr=jnp.asarray(9.0),
        b=jnp.ones((3, 1)),
        b_hat=jnp.asarray([[1.0], [0.8], [1.1]]),
        side=jnp.asarray(100.0),
        omega=jnp.asarray(0.0),
        fault_index=1,
        **kw,
    )


def test_controller_law_against_hand_formula():
    """Sec. II p_ij and eq. (3) for N = 3 on one axis, LLFR mode, checked by the constraint J(b_hat) u = p
    and the optimality condition sum alpha_i u_i / b_hat_i = 0 (E004-02)."""
    c = _law()
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


@pytest.mark.parametrize(("mode", "weighted"), [(1, None), (2, 2)])
def test_identified_allocation_meets_the_constraints_with_the_identified_gain(mode, weighted):
    """fault_estimate = "estimator": once the FDI has isolated (spacecraft 3, x) and identified its
    effectiveness 0.6, LLFR (and FLFR) allocate with b_hat_3 = b_3 0.6 -- checked by eq. (3)'s
    constraint J(b_hat) u = p and its optimality condition sum alpha_i u_i / b_hat_i = 0 (E004-02),
    with FLFR's alpha_flfr on the isolated spacecraft 3 (not on the stated fault_index 2)."""
    c = _law(fault_estimate="estimator")
    rd, _, _ = c.desired(0.0)
    e, ed = np.array([0.1, -0.2]), np.array([0.01, 0.03])
    y = {"position": (rd[1:] - rd[:-1]) + e[:, None], "velocity": jnp.asarray(ed[:, None])}
    iso = np.zeros((3, 3), dtype=bool)
    iso[2, 0] = True
    eff = np.ones((3, 3))
    eff[2, 0] = 0.6
    est = {
        "detected": np.asarray(True),
        "isolated": iso,
        "identified": np.ones((3, 3), dtype=bool),
        "effectiveness": eff,
    }
    inputs = FlightInputs(y, None, est, jnp.asarray(mode), None, None, None)
    u, _, out = c.output(0.0, c.initial_state(), inputs)
    u = np.asarray(u)[:, 0]
    b_hat = np.array([1.0, 0.8, 0.6])  # stated b_hat elsewhere, b * 0.6 on the identified channel
    alpha = np.array([1.0, 4.0, 9.0 if weighted == 2 else 2.0])
    p = -3.0 * ed - 2.0 * e
    np.testing.assert_allclose(
        [b_hat[1] * u[1] - b_hat[0] * u[0], b_hat[2] * u[2] - b_hat[1] * u[1]], p, rtol=1e-12
    )
    assert abs(np.sum(alpha * u / b_hat)) < 1e-12
    assert float(out["flfr_spacecraft"]) == 3.0


def test_chain_outputs_formed_on_board_from_the_relative_state_equal_the_measured_ones():
    """Given the (N, 6) relative state instead of the chain measurement, the law forms
    y_ij = q_{i+1} - q_i on its axes (numpy) and commands the same."""
    c = _law()
    q = np.random.default_rng(4).normal(size=(3, 6))
    chain = {"position": np.diff(q[:, :1], axis=0), "velocity": np.diff(q[:, 3:4], axis=0)}
    u_state, _, _ = c.output(
        0.3, c.initial_state(), FlightInputs(jnp.asarray(q), None, None, None, None, None, None)
    )
    u_chain, _, _ = c.output(
        0.3, c.initial_state(), FlightInputs(chain, None, None, None, None, None, None)
    )
    np.testing.assert_allclose(np.asarray(u_state), np.asarray(u_chain), rtol=0, atol=1e-15)


def test_force_law_is_rejected_on_the_acceleration_plant():
    loop = _loop()
    pd = PdFormationController(
        count=4, kp=jnp.asarray(1.0), kd=jnp.asarray(1.0), nominal_mass=jnp.ones(4)
    )
    with pytest.raises(CompositionError, match="force"):
        dataclasses.replace(loop, controller=pd).validate()


def test_continuous_law_needs_a_plant_with_rk4_stages():
    """sampling = 'continuous' on the exact-step double integrator: refused by validation, naming the
    law, the capability and the plant setting that provides it; accepted with integration = 'rk4'."""
    from formation_ftc.config.loader import ScenarioError

    with pytest.raises(ScenarioError, match=r"controller azizi2009-llfr needs RK4 integration"):
        _loop("azizi2009-llfr", **{"controller.sampling": "continuous"})
    loop = _loop(
        "azizi2009-llfr", **{"controller.sampling": "continuous", "plant.integration": "rk4"}
    )
    assert not loop.controller.sampled and loop.plant.integration == "rk4"
