"""Attitude scores (composed evaluation ``attitude-scores``): rotation angles against hand-computed ones,
the component's signals, the frame it reads in a composed loop, and rejection on a translational plant."""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components.evaluations.attitude_scores import (
    AttitudeScores,
    relative_angle,
    rotation_angle,
)
from formation_ftc.methods.composed import make_loop


def _axis_angle(axis, deg):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    h = math.radians(deg) / 2.0
    return np.concatenate([math.sin(h) * a, [math.cos(h)]])


def _dcm(q):
    """Rotation matrix of a vector-first unit quaternion, written out (numpy)."""
    x, y, z, w = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def _angle_between(p, q):
    """Angle of R(p)^T R(q) from its trace (independent of the quaternion formula)."""
    c = (np.trace(_dcm(p).T @ _dcm(q)) - 1.0) / 2.0
    return math.acos(min(1.0, max(-1.0, c)))


def test_ninety_degrees_about_z_and_the_double_cover():
    q = _axis_angle([0, 0, 1], 90.0)
    assert float(rotation_angle(jnp.asarray(q))) == pytest.approx(math.pi / 2, abs=1e-15)
    assert float(rotation_angle(jnp.asarray(-q))) == pytest.approx(math.pi / 2, abs=1e-15)
    assert float(rotation_angle(jnp.asarray(_axis_angle([1, 2, -1], 270.0)))) == pytest.approx(
        math.pi / 2, abs=1e-14
    )
    p = _axis_angle([1, 0, 0], 30.0)
    assert float(relative_angle(jnp.asarray(p), jnp.asarray(q))) == pytest.approx(
        _angle_between(p, q), abs=1e-12
    )


def test_signals_against_hand_computed_angles_and_torques():
    q = np.stack([_axis_angle([0, 0, 1], 90.0), [0.0, 0.0, 0.0, 1.0], _axis_angle([1, 0, 0], 30.0)])
    desired = np.tile([0.0, 0.0, 0.0, 1.0], (3, 1))
    applied = np.array([[3.0, 4.0, 0.0], [0.0, 0.0, 0.0], [1.0, 2.0, 2.0]])
    ev = AttitudeScores(desired_quaternion=desired, attitude_signal="attitude_lvlh")
    out = ev.outputs(
        {
            "attitude_lvlh": jnp.asarray(q),
            "quaternion": jnp.asarray(-desired),
            "applied": jnp.asarray(applied),
        }
    )
    np.testing.assert_allclose(
        np.asarray(out["attitude_error"]), [math.pi / 2, 0.0, math.pi / 6], atol=1e-14
    )
    sync = max(_angle_between(q[i], q[j]) for i, j in ((0, 1), (0, 2), (1, 2)))
    assert sync > math.pi / 2  # 90 deg about z against 30 deg about x: the largest pair
    assert float(out["attitude_synchronisation_error"]) == pytest.approx(sync, abs=1e-12)
    np.testing.assert_allclose(np.asarray(out["torque"]), [5.0, 0.0, 3.0], rtol=1e-15)
    # a desired attitude other than identity: the error of spacecraft 1 to 90 deg about z is zero
    ev2 = AttitudeScores(desired_quaternion=np.tile(q[0], (3, 1)), attitude_signal="attitude_lvlh")
    out2 = ev2.outputs({"attitude_lvlh": jnp.asarray(q), "applied": jnp.asarray(applied)})
    np.testing.assert_allclose(
        np.asarray(out2["attitude_error"])[:2], [0.0, math.pi / 2], atol=1e-14
    )


def _raw(frame, plant="attitude-truth"):
    p = {
        "type": plant,
        "inertia": [20.0, 25.0, 30.0],
        "initial_attitude_deg": [[0.0, 0.0, 30.0], [10.0, 0.0, 0.0]],
    }
    if plant == "attitude-truth":
        p.update(state_frame="lvlh", initial_frame="lvlh", initial_argument_of_latitude_deg=40.0)
    return {
        "scenario": {"name": "scores-test", "method": "composed"},
        "simulation": {"horizon": 1.0, "dt": 0.1, "record_every": 1},
        "plant": p,
        "controller": {"type": "attitude-pd", "K_p": 0.6, "K_d": 5.4},
        "evaluations": [{"type": "attitude-scores", "frame": frame}],
    }


def test_composed_scores_read_the_frame_asked_for():
    """On the truth at t = 0 the LVLH error is the initial LVLH attitude (30 deg yaw, 10 deg pitch); the
    inertial error adds the argument of latitude (40 deg about z); the torque is the norm of ``applied``."""
    lv = ftc.simulate(ftc.load_scenario(_raw("lvlh")))
    np.testing.assert_allclose(lv["attitude_error"].values[0], np.deg2rad([30.0, 10.0]), atol=1e-12)
    assert lv["attitude_synchronisation_error"].values[0] == pytest.approx(
        _angle_between(_axis_angle([0, 0, 1], 30.0), _axis_angle([0, 1, 0], 10.0)), abs=1e-12
    )
    np.testing.assert_allclose(
        lv["torque"].values, np.linalg.norm(lv["applied"].values, axis=-1), rtol=1e-14
    )
    assert np.all(lv["torque"].values[0] > 0.0)
    st = ftc.simulate(ftc.load_scenario(_raw("state")))  # state_frame = lvlh
    np.testing.assert_allclose(st["attitude_error"].values, lv["attitude_error"].values, atol=1e-15)
    ine = ftc.simulate(ftc.load_scenario(_raw("inertial")))
    assert ine["attitude_error"].values[0, 0] == pytest.approx(np.deg2rad(70.0), abs=1e-12)


def test_rejected_on_a_plant_without_attitude():
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
        "evaluations": [{"type": "attitude-scores"}],
    }
    with pytest.raises(
        Exception,
        match=r"evaluations\[0\] attitude-scores needs a plant whose state is \{omega \(N,3\), "
        r"q \(N,4\)\}.*to score its attitudes and torques.*\(provided by: plant type = "
        r'"quaternion-rigid-body" or "attitude-truth"\)',
    ):
        make_loop(ftc.load_scenario(raw))
    with pytest.raises(
        Exception,
        match=r"evaluations\[0\] attitude-scores needs the attitude relative to LVLH.*"
        r'\(provided by: plant type = "attitude-truth"\)',
    ):
        make_loop(ftc.load_scenario(_raw("lvlh", plant="quaternion-rigid-body")))
