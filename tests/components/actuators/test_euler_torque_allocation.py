"""Actuator ``euler-torque-allocation``: the generalised -> body torque map with the held additive
faults, one call against numpy truths (elementary rotations, R_bar written out, the power balance), and
the refusal on a plant without a quaternion."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components.actuators.euler_torque_allocation import (
    EulerTorqueAllocation,
    HeldAdditiveFaultActuator,
)
from formation_ftc.config.loader import ScenarioError
from formation_ftc.sim.components import ActuatorInputs, StepContext, as_float

RNG = np.random.default_rng(11)


def _quat(axis, angle):
    return np.concatenate([np.sin(angle / 2) * np.asarray(axis, float), [np.cos(angle / 2)]])


def _mul(p, q):  # Hamilton product, vector first
    pv, p4, qv, q4 = p[:3], p[3], q[:3], q[3]
    return np.concatenate([p4 * qv + q4 * pv + np.cross(pv, qv), [p4 * q4 - pv @ qv]])


def _rbar(th, ph):
    ct, st, cp, sp = np.cos(th), np.sin(th), np.cos(ph), np.sin(ph)
    return np.array([[0, cp, -sp], [1, sp * st / ct, cp * st / ct], [0, sp / ct, cp / ct]])


def _state(n):
    angles = np.stack(
        [np.deg2rad(RNG.uniform(-80, 80, n)), RNG.uniform(-3, 3, n), RNG.uniform(-3, 3, n)], -1
    )
    # quaternion built from elementary rotations: yaw about z, then pitch about y, then roll about x
    p = np.array(
        [
            _mul(_mul(_quat([0, 0, 1], ps), _quat([0, 1, 0], th)), _quat([1, 0, 0], ph))
            for th, ph, ps in angles
        ]
    )
    p *= np.where(RNG.uniform(size=(n, 1)) < 0.5, -1.0, 1.0)  # either sign of the same attitude
    return angles, {"omega": RNG.normal(size=(n, 3)), "q": jnp.asarray(1.0001 * p)}


def test_allocation_maps_command_plus_fault_to_the_body_torque_of_equal_power():
    n = 4
    angles, x = _state(n)
    inner = HeldAdditiveFaultActuator(
        count=n,
        windows=as_float([[0.0, 10.0]]),
        torques=("0.7",),
        spacecraft=(2,),
        channels=(1,),
    )
    act = EulerTorqueAllocation(inner=inner)
    assert act.holds_exogenous and act.count == n
    assert {s.name for s in act.signals()} == {"fault", "generalised_applied", "attitude"}
    u = RNG.normal(size=(n, 3))
    inputs = ActuatorInputs(
        act.held_exogenous(StepContext(jnp.asarray(10), jnp.asarray(1.0), 0.1)), None, None, x
    )
    tau_body = np.asarray(act.apply(1.0, jnp.asarray(u), inputs))
    gen = u.copy()
    gen[2, 1] += 0.7  # the fault acts in spacecraft 3's roll channel before the map
    for k in range(n):
        R = _rbar(angles[k, 0], angles[k, 1])
        np.testing.assert_allclose(tau_body[k], R.T @ gen[k], rtol=1e-10, atol=1e-12)
        w = np.asarray(x["omega"][k])
        np.testing.assert_allclose(
            tau_body[k] @ w, gen[k] @ (R @ w), rtol=1e-10, atol=1e-12
        )  # power
    out = act.outputs(1.0, jnp.asarray(u), inputs)
    np.testing.assert_allclose(np.asarray(out["generalised_applied"]), gen, atol=1e-14)
    np.testing.assert_allclose(np.asarray(out["attitude"]), angles, atol=1e-12)
    # without an inner chain the map is applied to the command alone
    bare = EulerTorqueAllocation()
    assert not bare.holds_exogenous and bare.count is None
    np.testing.assert_allclose(
        np.asarray(bare.apply(0.0, jnp.asarray(u), ActuatorInputs(None, None, None, x))),
        np.stack([_rbar(*angles[k, :2]).T @ u[k] for k in range(n)]),
        rtol=1e-10,
        atol=1e-12,
    )
    # what the allocation needs and provides (the faults it carries: the scripted FDI's report)
    assert act.needs().keys() == {"quaternion-attitude-state"}
    assert act.provides() == {"generalised-torque-actuation", "scripted-actuator-faults"}
    assert bare.provides() == {"generalised-torque-actuation"}


def test_allocation_on_a_plant_without_quaternion_is_refused():
    raw = {
        "scenario": {"name": "t", "method": "composed"},
        "simulation": {"horizon": 1.0, "dt": 0.1},
        "plant": {
            "type": "clohessy-wiltshire",
            "semi_major_axis": 7.0e6,
            "mass": [100.0],
            "initial_position": [[1.0, 0.0, 0.0]],
        },
        "controller": {"type": "pd", "kp": 1.0, "kd": 1.0},
        "actuator": {"type": "euler-torque-allocation"},
    }
    with pytest.raises(ScenarioError) as err:
        ftc.load_scenario(raw)
    msg = str(err.value)
    assert (
        "actuator euler-torque-allocation needs a plant whose state is {omega (N,3), q (N,4)}"
        in msg
    )
    assert '(provided by: plant type = "quaternion-rigid-body" or "attitude-truth")' in msg
    raw["actuator"]["faults"] = [
        {"spacecraft": 2, "channel": 1, "torque": "0.5", "start": 0.0, "end": 1.0}
    ]
    with pytest.raises(
        ScenarioError, match=r"actuator.faults\[0\].spacecraft = 2: the plant has 1"
    ):
        ftc.load_scenario(raw)
