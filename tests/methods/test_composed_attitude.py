"""Composition ``compose-mehrabian-on-yang2013``: Mehrabian's Euler-angle attitude law flying Yang2013's
quaternion rigid bodies through the 3-2-1 Euler sensors and the generalised-torque allocation."""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.cli import main
from formation_ftc.components.plants.euler_angle_attitude import EulerAngleAttitudePlant
from formation_ftc.config.loader import ScenarioError
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import PerfectSensors, as_float

NAME = "compose-mehrabian-on-yang2013"


def _rbar_numpy(q):
    """R_bar(q) of q_dot = R_bar omega for q = [theta, phi, psi] (3-2-1), written out in numpy."""
    th, ph = q[..., 0], q[..., 1]
    ct, st, cp, sp = np.cos(th), np.sin(th), np.cos(ph), np.sin(ph)
    z, o = np.zeros_like(th), np.ones_like(th)
    return np.stack(
        [
            np.stack([z, cp, -sp], -1),
            np.stack([o, sp * st / ct, cp * st / ct], -1),
            np.stack([z, sp / ct, cp / ct], -1),
        ],
        -2,
    )


def _dcm_numpy(q):
    """Rz(psi) Ry(theta) Rx(phi) from elementary rotations."""
    out = []
    for th, ph, ps in q.reshape(-1, 3):
        cz, sz, cy, sy, cx, sx = (
            np.cos(ps),
            np.sin(ps),
            np.cos(th),
            np.sin(th),
            np.cos(ph),
            np.sin(ph),
        )
        Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
        Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
        Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
        out.append(Rz @ Ry @ Rx)
    return np.array(out).reshape(q.shape[:-1] + (3, 3))


def _dcm_of_quaternion_numpy(p):
    p = p / np.linalg.norm(p, axis=-1, keepdims=True)
    v, s = p[..., :3], p[..., 3]
    skew = np.zeros(p.shape[:-1] + (3, 3))
    skew[..., 0, 1], skew[..., 0, 2], skew[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    skew -= np.swapaxes(skew, -1, -2)
    return (
        (s**2 - np.sum(v * v, -1))[..., None, None] * np.eye(3)
        + 2 * v[..., :, None] * v[..., None, :]
        + 2 * s[..., None, None] * skew
    )


def test_scenario_runs_records_metrics_check_and_the_conversions_hold():
    fault = {
        "spacecraft": 1,
        "channel": 3,
        "torque": "0.05*sin(0.02*t) + 0.6",
        "start": 2.0,
        "end": 8.0,
    }
    scn = ftc.load_scenario(NAME, {"simulation.horizon": 10.0, "actuator.faults": [fault]})
    ds, m = ftc.simulate_with_metrics(scn)
    for var in (
        "quaternion",
        "angular_velocity",
        "attitude",
        "tracking_error",
        "synchronisation_error",
        "command",
        "generalised_applied",
        "applied",
        "fault",
        "fdi_flag",
        "fault_estimate_adaptive",
    ):
        assert var in ds, var
    assert ds.sizes["spacecraft"] == 8 and ds.sizes["time"] == 11
    t = ds.time.values
    # the attitude the allocation uses is the plant's quaternion in 3-2-1 angles (independent DCMs)
    np.testing.assert_allclose(
        _dcm_numpy(ds.attitude.values), _dcm_of_quaternion_numpy(ds.quaternion.values), atol=1e-12
    )
    # the law saw the same angles through the sensors (desired attitude 0: tracking error = attitude)
    np.testing.assert_allclose(ds.tracking_error.values, ds.attitude.values, atol=1e-12)
    # truth-side fault: spacecraft 1, yaw channel, on [2, 8] s only, added in the law's channels
    expected = np.zeros_like(ds.fault.values)
    on = (t >= 2.0) & (t <= 8.0)
    expected[on, 0, 2] = 0.05 * np.sin(0.02 * t[on]) + 0.6
    np.testing.assert_allclose(ds.fault.values, expected, atol=1e-12)
    np.testing.assert_allclose(
        ds.generalised_applied.values - ds.command.values, ds.fault.values, atol=1e-12
    )
    # body torque = R_bar(q)^T (tau_gen + u_bar), and it does the same work on omega as tau_gen on q_dot
    tau_gen, q, w = ds.generalised_applied.values, ds.attitude.values, ds.angular_velocity.values
    R = _rbar_numpy(q)
    np.testing.assert_allclose(
        ds.applied.values, np.einsum("...ji,...j->...i", R, tau_gen), atol=1e-12
    )
    qdot = np.einsum("...ij,...j->...i", R, w)
    np.testing.assert_allclose(
        np.sum(ds.applied.values * w, -1), np.sum(tau_gen * qdot, -1), atol=1e-12
    )
    # the FDI flags spacecraft 1 yaw after the 5 s latency; the adaptive estimate then moves off zero
    flag = ds.fdi_flag.values[:, 0, 2]
    np.testing.assert_array_equal(flag, (t >= 7.0).astype(float))
    assert np.all(ds.fault_estimate_adaptive.values[t < 7.0] == 0.0)
    assert abs(ds.fault_estimate_adaptive.values[-1, 0, 2]) > 1e-3
    # unit quaternions are kept (RK4 drift only); the law synchronises the attitudes within seconds (the
    # common mode of the literal law (8) with alpha = 0.86 is barely damped, so tracking is slower)
    np.testing.assert_allclose(np.linalg.norm(ds.quaternion.values, axis=-1), 1.0, atol=1e-9)
    sync = np.linalg.norm(ds.synchronisation_error.values, axis=-1).mean(axis=1)
    assert sync[-1] < 0.5 * sync[0]
    e = np.linalg.norm(ds.tracking_error.values, axis=-1).mean(axis=1)
    assert e[-1] < e[0]
    assert set(m) == {
        "track_err_rms",
        "track_err_max_after_45s",
        "sync_err_max_after_45s",
        "final_track_err_max",
        "body_torque_max",
        "control_effort",
    }
    assert np.isnan(m.pop("track_err_max_after_45s")) and np.isnan(
        m.pop("sync_err_max_after_45s")
    )  # window > 10 s
    assert all(np.isfinite(v) for v in m.values())
    conds = {c.name: c for c in ftc.check(scn)}
    # the law's theorem conditions (registered by papers/mehrabian) come with it on this plant too;
    # the RK4 step estimate is a heuristic (holds None: unproven)
    assert {"components fit together", "0 < alpha < 1", "P_j positive definite"} <= set(conds)
    assert all(c.holds is not False for c in conds.values())
    assert all(c.holds for c in conds.values() if c.required)


def test_composition_equals_the_law_on_the_euler_angle_plant():
    """The same law, fault and FDI on Mehrabian's Euler-angle plant (rigid body in (q, omega) with the
    body torque R_bar^T u) give the same trajectory: only the attitude coordinates differ."""
    angles_deg = [[10.0, 40.0, -20.0], [55.0, -30.0, 120.0], [-25.0, 5.0, 60.0]]
    raw = {
        "scenario": {"name": "eq", "method": "composed"},
        "simulation": {"horizon": 6.0, "dt": 0.01, "record_every": 50, "seed": 3},
        "plant": {
            "type": "quaternion-rigid-body",
            "inertia": [20.0, 18.0, 15.0],
            "initial_attitude_deg": angles_deg,
            "initial_body_rate": [[0.01, -0.02, 0.03], [0.0, 0.0, 0.0], [-0.01, 0.02, 0.0]],
        },
        "sensors": {"type": "quaternion-euler"},
        "controller": {
            "type": "networked-el-hinf",
            "edges": [[1, 2], [2, 3]],
            "desired_attitude": ["0.1*sin(0.2*t)", "0", "0.05*i"],
        },
        "actuator": {
            "type": "euler-torque-allocation",
            "faults": [{"spacecraft": 2, "channel": 1, "torque": "0.5", "start": 1.0, "end": 4.0}],
        },
        "estimator": {"type": "scripted-fdi", "delay": 1.0, "bias": -0.1},
    }
    scn = ftc.load_scenario(raw)
    loop = make_loop(scn)
    a = ftc.simulate(scn)
    q0 = np.deg2rad(np.asarray(angles_deg))
    w0 = np.asarray(raw["plant"]["initial_body_rate"])
    euler_plant = EulerAngleAttitudePlant(
        seed=jnp.asarray(3, jnp.uint32),
        random_initial_attitude=as_float(0.0),
        q0_range=as_float([0.0, 1.0]),
        q0_fixed=as_float(q0),
        qdot0=as_float(np.einsum("kij,kj->ki", _rbar_numpy(q0), w0)),
        inertia=as_float(np.tile([20.0, 18.0, 15.0], (3, 1))),
        inertia_uncertainty=as_float(0.0),
        disturbance_std=as_float(0.0),
    )
    ref = dataclasses.replace(
        loop, plant=euler_plant, sensors=PerfectSensors(), actuator=loop.actuator.inner
    )
    c = ref.validate()
    out = jax.jit(type(c).run)(c)
    b = c.dataset(out, int(np.shape(out["records"]["command"])[0]))
    assert np.abs(b.tracking_error.values).max() > 0.1 and np.abs(b.fault.values).max() == 0.5
    for var in ("tracking_error", "command", "synchronisation_error", "fault_estimate_adaptive"):
        np.testing.assert_allclose(a[var].values, b[var].values, rtol=0, atol=1e-9, err_msg=var)
    np.testing.assert_allclose(a.attitude.values, b.attitude.values, rtol=0, atol=1e-9)


def _raw(**slots):
    base = {
        "scenario": {"name": "bad", "method": "composed"},
        "simulation": {"horizon": 1.0, "dt": 0.01},
        "plant": {
            "type": "quaternion-rigid-body",
            "inertia": [20.0, 18.0, 15.0],
            "initial_attitude_deg": [[10.0, 0.0, 0.0], [0.0, 20.0, 0.0], [0.0, 0.0, 30.0]],
        },
        "sensors": {"type": "quaternion-euler"},
        "controller": {"type": "networked-el-hinf", "edges": [[1, 2], [2, 3]]},
        "actuator": {"type": "euler-torque-allocation"},
    }
    base.update(slots)
    return {k: v for k, v in base.items() if v is not None}


CW = {
    "type": "clohessy-wiltshire",
    "semi_major_axis": 7000e3,
    "mass": [10.0, 10.0, 10.0],
    "initial_position": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
}
EL_LAW = {
    "type": "networked-el-hinf",
    "edges": [[1, 2], [2, 3]],
    "nominal_inertia": [20.0, 18.0, 15.0],
}


@pytest.mark.parametrize(
    "slots, needles",
    [
        # an attitude law on a translational plant: the quantities differ
        (
            {"plant": CW, "sensors": None, "actuator": None, "controller": EL_LAW},
            ("controller networked-el-hinf", "plant clohessy-wiltshire", "torque", "force"),
        ),
        # the Euler-angle law on the quaternion plant without the conversions: validation names the
        # law, what it needs and who provides it
        (
            {"sensors": None},
            (
                "controller networked-el-hinf needs 3-2-1 Euler angles",
                'sensors type = "quaternion-euler" on a quaternion plant ("quaternion-rigid-body"',
            ),
        ),
        (
            {"actuator": None},
            (
                "controller networked-el-hinf needs an actuator applying the generalised torque",
                'actuator type = "euler-torque-allocation"',
            ),
        ),
        # the conversions on a plant that has no quaternion
        (
            {"plant": CW, "controller": {"type": "pd", "kp": 1.0, "kd": 1.0}, "actuator": None},
            ("sensors quaternion-euler needs a plant whose state is", '"quaternion-rigid-body"'),
        ),
        (
            {"controller": {"type": "networked-el-hinf", "edges": [[1, 2], [2, 4]]}},
            ("controller.edges[1] = [2, 4]", "3 spacecraft"),
        ),
        ({"controller": {"type": "networked-el-hinf", "edges": [[1, 2]]}}, ("not connected",)),
        (
            {"estimator": {"type": "scripted-fdi"}},
            ("estimator scripted-fdi needs additive actuator faults", "euler-torque-allocation"),
        ),
        (
            {
                "plant": {
                    "type": "quaternion-rigid-body",
                    "inertia": [1.0, 1.0, 1.0],
                    "initial_attitude_deg": [[88.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]],
                }
            },
            ("pitch", "singular"),
        ),
        (
            {
                "controller": {
                    "type": "networked-el-hinf",
                    "edges": [[1, 2], [2, 3]],
                    "law": "bogus",
                }
            },
            ("controller.law",),
        ),
        (
            {
                "plant": {
                    "type": "quaternion-rigid-body",
                    "inertia": [1.0, -1.0, 1.0],
                    "initial_quaternion": [[0, 0, 0, 1]] * 3,
                }
            },
            ("plant.inertia", "[1] = "),
        ),
    ],
)
def test_impossible_compositions_are_rejected_at_validation(slots, needles):
    with pytest.raises(ScenarioError) as err:
        ftc.load_scenario(_raw(**slots))
    for needle in needles:
        assert needle in str(err.value), (needle, str(err.value))


def test_cli_rejects_an_attitude_law_on_a_translational_plant_with_exit_2(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text("""
[scenario]
name = "bad"
method = "composed"
[simulation]
horizon = 1.0
dt = 0.01
[plant]
type = "clohessy-wiltshire"
semi_major_axis = 7000e3
mass = [10.0, 10.0]
initial_position = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
[controller]
type = "networked-el-hinf"
edges = [[1, 2]]
nominal_inertia = [20.0, 18.0, 15.0]
""")
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert (
        "controller networked-el-hinf" in err
        and "plant clohessy-wiltshire" in err
        and "torque" in err
    )
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
