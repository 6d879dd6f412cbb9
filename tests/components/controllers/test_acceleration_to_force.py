"""The acceleration-to-force adapter and the chain sensors on an (N, 6) relative state, against
independent numpy formulas; the adapter sees only flight inputs and rejects a law that is no
acceleration law."""

from __future__ import annotations

import dataclasses
import inspect
import typing

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from formation_ftc.components.controllers._acceleration_to_force import (
    AccelerationToForce,
    TrackingAccelerationToForce,
    force_from_acceleration,
)
from formation_ftc.components.controllers.azizi2009_llfr import ChainLlfrController
from formation_ftc.components.controllers.pd import PdFormationController
from formation_ftc.components.sensors.chain_relative import (
    ChainRelativeSensors,
    ChainRelativeStateSensors,
)
from formation_ftc.sim.batch import stack_params
from formation_ftc.sim.components import CompositionError, FlightInputs, SensorInputs, as_float

MASS = np.array([100.0, 120.0, 115.0, 108.0])


def _law(sampled=True):
    return ChainLlfrController(
        lambda0=as_float(2.0),
        lambda1=as_float(3.0),
        alpha=as_float(np.ones(4)),
        alpha_flfr=as_float(4.7),
        b=as_float(np.ones((4, 3))),
        b_hat=as_float(np.array([[1, 1, 1], [0.88, 1, 1], [1, 1, 1], [1, 1, 1.0]])),
        side=as_float(200.0),
        omega=as_float(0.1),
        fault_index=1,
        is_sampled=sampled,
    )


def _chain_y(seed=0):
    rng = np.random.default_rng(seed)
    return {
        "position": jnp.asarray(rng.normal(size=(3, 3)) * 100),
        "velocity": jnp.asarray(rng.normal(size=(3, 3))),
    }


def test_force_is_nominal_mass_times_the_laws_acceleration_in_every_mode():
    law = _law()
    ctl = force_from_acceleration(law, as_float(MASS))
    assert type(ctl) is AccelerationToForce  # the chain law has no absolute position objective
    assert ctl.quantity == "force" and law.quantity == "acceleration"
    assert ctl.sampled and ctl.count == 4
    y = _chain_y()
    for mode in (0, 1, 2):
        flight = FlightInputs(y, None, None, jnp.asarray(mode), None, None, None)
        u, _, out = law.output(jnp.asarray(2.5), law.initial_state(), flight)
        f, nxt, out_f = ctl.output(jnp.asarray(2.5), ctl.initial_state(), flight)
        np.testing.assert_allclose(np.asarray(f), MASS[:, None] * np.asarray(u), rtol=1e-15)
        np.testing.assert_array_equal(np.asarray(out_f["acceleration_command"]), np.asarray(u))
        np.testing.assert_array_equal(
            np.asarray(out_f["desired_position"]), np.asarray(out["desired_position"])
        )
        np.testing.assert_array_equal(
            np.asarray(nxt["allocation"]), np.asarray(law.initial_state()["allocation"])
        )
    names = [s.name for s in ctl.signals()]
    assert names == ["desired_position", "acceleration_command"]
    assert ctl.coords() == law.coords()


def test_adapter_output_takes_flight_inputs_only_and_is_a_pytree():
    hints = typing.get_type_hints(AccelerationToForce.output)
    assert hints["inputs"] is FlightInputs
    assert list(inspect.signature(AccelerationToForce.output).parameters) == [
        "self",
        "t",
        "state",
        "inputs",
    ]
    ctl = force_from_acceleration(_law(), as_float(MASS))
    leaves, treedef = jax.tree_util.tree_flatten(ctl)
    assert any(
        np.array_equal(np.asarray(leaf), MASS) for leaf in leaves
    )  # the masses are a leaf (batchable)
    again = jax.tree_util.tree_unflatten(treedef, leaves)
    assert type(again) is AccelerationToForce and again.law.fault_index == 1
    # a batch that varies the masses and a law leaf stacks without tripping any construction check
    other = force_from_acceleration(
        dataclasses.replace(_law(), alpha_flfr=as_float(2.0)), as_float(MASS * 1.1)
    )
    batch, axes = stack_params([ctl, other])
    assert (
        np.shape(batch.nominal_mass) == (2, 4)
        and axes.nominal_mass == 0
        and axes.law.lambda0 is None
    )


def test_adapter_keeps_a_position_objective_and_rejects_other_quantities():
    pd = PdFormationController(
        count=4,
        kp=as_float(1.0),
        kd=as_float(1.0),
        nominal_mass=as_float(MASS),
        max_force=as_float(np.inf),
    )
    with pytest.raises(CompositionError, match="PdFormationController commands a force"):
        force_from_acceleration(pd, as_float(MASS))
    with pytest.raises(CompositionError, match="ChainLlfrController of 4 spacecraft"):
        force_from_acceleration(_law(), as_float(MASS[:3]))
    with pytest.raises(CompositionError, match="each > 0"):
        force_from_acceleration(_law(), as_float([100.0, np.inf, 1.0, 1.0]))

    class _Tracking(ChainLlfrController):  # the chain law with a position objective (test double)
        def desired_position_at(self, exogenous):
            return exogenous

    tracking = _Tracking(**{f: getattr(_law(), f) for f in _law().__dataclass_fields__})
    assert type(force_from_acceleration(tracking, as_float(MASS))) is TrackingAccelerationToForce


def test_chain_sensors_on_the_relative_state_match_numpy_differences_and_noise_streams():
    rng = np.random.default_rng(3)
    q = rng.normal(size=(4, 6)) * 300
    exact = ChainRelativeStateSensors(count=4, n_axes=3)
    y = exact.measure(0.0, {"q": jnp.asarray(q)}, SensorInputs(None, None))
    np.testing.assert_allclose(np.asarray(y["position"]), q[1:, :3] - q[:-1, :3], rtol=1e-15)
    np.testing.assert_allclose(np.asarray(y["velocity"]), q[1:, 3:] - q[:-1, 3:], rtol=1e-15)
    # with noise: the same draws as the r/v sensors on the same key (same streams), added to the differences
    kw = dict(
        count=4,
        n_axes=3,
        position_noise_std=as_float(0.5),
        velocity_noise_std=as_float(0.01),
        noisy=True,
    )
    s_q, s_rv = ChainRelativeStateSensors(**kw), ChainRelativeSensors(**kw)
    key = jax.random.PRNGKey(7)
    n_q, n_rv = s_q.noise(key), s_rv.noise(key)
    y_q = s_q.measure(0.0, {"q": jnp.asarray(q)}, SensorInputs(n_q, None))
    y_rv = s_rv.measure(
        0.0, {"r": jnp.asarray(q[:, :3]), "v": jnp.asarray(q[:, 3:])}, SensorInputs(n_rv, None)
    )
    for k in ("position", "velocity"):
        np.testing.assert_allclose(np.asarray(y_q[k]), np.asarray(y_rv[k]), rtol=1e-15)
    assert np.std(np.asarray(y_q["position"]) - (q[1:, :3] - q[:-1, :3])) > 0.05
