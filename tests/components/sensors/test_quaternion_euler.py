"""Sensors ``quaternion-euler``: quaternion -> 3-2-1 Euler angles against elementary rotations, body
rates passed through; what they need and provide."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from formation_ftc.components.sensors.quaternion_euler import QuaternionToEulerSensors
from formation_ftc.sim.components import SensorInputs

RNG = np.random.default_rng(11)


def _quat(axis, angle):
    return np.concatenate([np.sin(angle / 2) * np.asarray(axis, float), [np.cos(angle / 2)]])


def _mul(p, q):  # Hamilton product, vector first
    pv, p4, qv, q4 = p[:3], p[3], q[:3], q[3]
    return np.concatenate([p4 * qv + q4 * pv + np.cross(pv, qv), [p4 * q4 - pv @ qv]])


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


def test_sensors_report_3_2_1_angles_and_body_rates():
    angles, x = _state(40)
    y = QuaternionToEulerSensors(count=40).measure(0.0, x, SensorInputs(None, None))
    np.testing.assert_allclose(np.asarray(y["q"]), angles, atol=1e-12)
    np.testing.assert_allclose(np.asarray(y["w"]), np.asarray(x["omega"]), atol=0)
    sensors = QuaternionToEulerSensors(count=40)
    assert sensors.needs().keys() == {"quaternion-attitude-state"}
    assert sensors.provides() == {"euler-angle-measurement"}
