"""Attitude truth plant (quaternion rigid bodies on a circular orbit with gravity gradient).

Truths: torque-free invariants (inertial angular momentum, kinetic energy, quaternion norm) over a long
RK4 run with full per-spacecraft inertias; the Jacobi integral under gravity gradient; the small-angle
pitch libration period (zero crossings) and the roll/yaw libration frequencies (least-squares fit)
against the closed forms of :mod:`formation_ftc.core.dynamics.gravity_gradient`; the LVLH-aligned
equilibrium rotating at the orbit rate; the composed plant type: the LVLH initial frame, the recorded
gravity-gradient torque and usage integral against independent numpy values, and rejection of bad
sections with messages naming the field.
"""

from __future__ import annotations

import math
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components.plants.attitude_truth import (
    AttitudeTruthPlant,
    initial_inertial_state,
)
from formation_ftc.config.loader import ScenarioError
from formation_ftc.core.dynamics.gravity_gradient import (
    jacobi_integral,
    pitch_libration_frequency,
    roll_yaw_libration_frequencies,
)
from formation_ftc.core.integrators import rk4_step
from formation_ftc.core.orbit import MU_EARTH
from formation_ftc.sim.components import as_float

A = 7.0e6
N = math.sqrt(MU_EARTH / A**3)
SCENARIO = "compose-mehrabian-on-attitude-truth"


def _plant(J, w0, q0, gg=True, u0=0.0, frame="inertial"):
    J = np.asarray(J, float)
    w0 = np.atleast_2d(np.asarray(w0, float))
    if J.ndim == 2:
        J = np.broadcast_to(J, (w0.shape[0], 3, 3)).copy()
    return AttitudeTruthPlant(
        inertia=as_float(J),
        initial_body_rate=as_float(w0),
        initial_quaternion=as_float(np.atleast_2d(q0)),
        semi_major_axis=as_float(A),
        mu=as_float(MU_EARTH),
        initial_argument_of_latitude=as_float(u0),
        gravity_gradient=gg,
        state_frame=frame,
    )


@partial(jax.jit, static_argnames="n_steps")
def _run(plant, x0, dt, n_steps):
    zero = jnp.zeros((plant.count, 3))

    def body(x, k):
        x = rk4_step(lambda t, y: plant.rates(t, y, zero), k * dt, x, dt)
        return x, x

    return jax.lax.scan(body, x0, jnp.arange(n_steps))[1]


def _propagate(plant, dt, n_steps):
    """RK4 of the plant without applied torque; returns (times (n+1,), omega (n+1, N, 3), q (n+1, N, 4))."""
    x0 = jax.tree_util.tree_map(jnp.asarray, plant.initial_state())
    traj = _run(plant, x0, jnp.asarray(dt), n_steps)
    w = np.concatenate([np.asarray(x0["omega"])[None], np.asarray(traj["omega"])])
    q = np.concatenate([np.asarray(x0["q"])[None], np.asarray(traj["q"])])
    return dt * np.arange(n_steps + 1), w, q


def _dcm(p):
    x, y, z, w = np.moveaxis(p / np.linalg.norm(p, axis=-1, keepdims=True), -1, 0)
    return np.stack(
        [
            np.stack([w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z], -1),
        ],
        -2,
    )


def _rz(u):
    return np.array([0.0, 0.0, math.sin(u / 2), math.cos(u / 2)])


def _lvlh_angles(q, t, u0=0.0):
    """(yaw about x, roll about y, pitch about z) small angles of the body relative to LVLH, from numpy
    DCMs: C_BL = Rz(u)^T C(q) ~ I + [a]x for small a."""
    u = u0 + N * t
    c, s = np.cos(u), np.sin(u)
    Rz = np.zeros((len(t), 3, 3))
    Rz[:, 0, 0], Rz[:, 0, 1], Rz[:, 1, 0], Rz[:, 1, 1], Rz[:, 2, 2] = c, -s, s, c, 1.0
    C = np.einsum("tji,tjk->tik", Rz, _dcm(q))  # Rz^T C
    return np.stack([C[:, 2, 1], C[:, 0, 2], C[:, 1, 0]], axis=-1)


def test_torque_free_invariants_over_a_long_run():
    """gravity gradient off: L = C(q) J omega, T = 1/2 omega^T J omega, |q| = 1 (two tumbling bodies,
    full inertias), 2000 s (~100 tumbling periods) with dt = 0.05 s. Measured: max ||q| - 1| = 1.6e-10,
    max |dT|/T = 1.9e-11, max |dL|/|L| = 3.6e-10 (bounds about 5x those)."""
    J1 = np.array([[25.0, 1.5, -0.8], [1.5, 30.0, 0.6], [-0.8, 0.6, 18.0]])
    J2 = np.diag([12.0, 20.0, 27.0])
    q0 = np.array([[0.1, -0.3, 0.2, 0.9], [0.0, 0.0, 0.0, 1.0]])
    q0 /= np.linalg.norm(q0, axis=1, keepdims=True)
    plant = _plant(np.stack([J1, J2]), [[0.05, -0.2, 0.3], [0.01, 0.3, 0.02]], q0, gg=False)
    _, w, q = _propagate(plant, 0.05, 40000)
    Js = np.stack([J1, J2])
    L = np.einsum("tnij,njk,tnk->tni", _dcm(q), Js, w)
    T = 0.5 * np.einsum("tni,nij,tnj->tn", w, Js, w)
    dq = np.abs(np.linalg.norm(q, axis=-1) - 1.0).max()
    dT = (np.abs(T - T[0]) / T[0]).max()
    dL = (np.linalg.norm(L - L[0], axis=-1) / np.linalg.norm(L[0], axis=-1)).max()
    assert dq < 1e-9 and dT < 1e-10 and dL < 2e-9, (dq, dT, dL)


def test_jacobi_integral_conserved_under_gravity_gradient():
    """Tumbling body (inertial rates ~ 10 n) under gravity gradient over 2 orbits, dt = 2 s: the Jacobi
    integral holds to RK4 accuracy (measured max |dH|/|H| = 1.4e-10, bound 1e-8) while the gravity
    gradient changes the kinetic energy by 1.6 % (so the torque acts)."""
    J = np.diag([10.0, 20.0, 25.0])
    q0 = np.array([0.2, -0.1, 0.3, 0.9])
    q0 /= np.linalg.norm(q0)
    plant = _plant(J, [3 * N, -5 * N, 8 * N], q0, u0=0.4)
    t, w, q = _propagate(plant, 2.0, int(2 * 2 * math.pi / N / 2.0))
    H = np.asarray(jacobi_integral(w[:, 0], q[:, 0], J, 0.4 + N * t, N))
    T = 0.5 * np.einsum("ti,ij,tj->t", w[:, 0], J, w[:, 0])
    rel = np.abs(H - H[0]).max() / abs(H[0])
    assert rel < 1e-8, rel
    assert np.abs(T - T[0]).max() / T[0] > 1e-3  # not a torque-free run in disguise


def test_pitch_libration_period_against_closed_form():
    """Small pitch offset (1 deg) about LVLH alignment, body rate n about the orbit normal: the pitch
    oscillates at n sqrt(3 (J_y - J_x) / J_z). Period from the zero crossings over ~4 librations
    (dt = 5 s): measured 7.6e-5 above the small-angle value (tolerance 1e-3), which is exactly the
    finite-amplitude correction th0^2 / 4 of th'' = -(w^2 / 2) sin(2 th) (agreement with it 1e-8, tolerance
    1e-6); roll and yaw stay 0."""
    J = np.diag([10.0, 20.0, 25.0])
    th0 = math.radians(1.0)
    plant = _plant(J, [0.0, 0.0, N], _rz(th0))
    w_p = pitch_libration_frequency((10.0, 20.0, 25.0), N)
    period = 2 * math.pi / w_p
    dt = 5.0
    t, _, q = _propagate(plant, dt, int(4.3 * period / dt))
    ang = _lvlh_angles(q[:, 0], t)
    pitch = ang[:, 2]
    idx = np.nonzero(np.sign(pitch[:-1]) != np.sign(pitch[1:]))[0]
    crossings = t[idx] - pitch[idx] * dt / (pitch[idx + 1] - pitch[idx])  # linear interpolation
    assert len(crossings) >= 8
    measured = 2.0 * np.mean(np.diff(crossings))
    assert measured == pytest.approx(period, rel=1e-3), (measured, period)
    assert measured == pytest.approx(period * (1.0 + th0**2 / 4.0), rel=1e-6), (measured, period)
    assert np.abs(pitch).max() == pytest.approx(
        math.sin(th0), rel=1e-4
    )  # amplitude: the initial offset
    assert np.abs(ang[:, :2]).max() < 1e-12  # planar motion stays planar


def test_roll_yaw_libration_frequencies_against_closed_form():
    """Small roll offset (0.05 deg about the along-track axis), 8 slow periods, dt = 10 s: the roll/yaw
    motion is the sum of the two modes of the closed form; a least-squares fit of cos / sin at those
    frequencies leaves an rms residual of 5.1e-6 of the amplitude (it scales with the amplitude squared:
    nonlinear terms), while either frequency 0.1 % off leaves >= 3.9e-4 (measured)."""
    J = np.diag([10.0, 20.0, 25.0])
    ph0 = math.radians(0.05)
    q0 = np.array([0.0, math.sin(ph0 / 2), 0.0, math.cos(ph0 / 2)])
    plant = _plant(J, [0.0, 0.0, N], q0)
    w1, w2 = roll_yaw_libration_frequencies((10.0, 20.0, 25.0), N)
    dt = 10.0
    t, _, q = _propagate(plant, dt, int(8 * 2 * math.pi / w1 / dt))
    roll = _lvlh_angles(q[:, 0], t)[:, 1]

    def residual(f1, f2):
        B = np.stack([np.cos(f1 * t), np.sin(f1 * t), np.cos(f2 * t), np.sin(f2 * t)], axis=1)
        coef, *_ = np.linalg.lstsq(B, roll, rcond=None)
        return np.sqrt(np.mean((B @ coef - roll) ** 2)) / ph0

    good = residual(w1, w2)
    assert good < 5e-5, good
    assert residual(1.001 * w1, w2) > 10 * good and residual(w1, 1.001 * w2) > 10 * good


def test_lvlh_aligned_body_rotating_at_orbit_rate_stays_aligned():
    """Equilibrium: body axes = LVLH axes at u0, body rate n about the orbit normal; over one orbit the
    attitude relative to LVLH stays the identity (measured 2e-12 rad, bound 1e-10) and the torque ~ 0."""
    J = np.diag([10.0, 20.0, 25.0])
    u0 = 0.7
    plant = _plant(J, [0.0, 0.0, N], _rz(u0), u0=u0)
    t, w, q = _propagate(plant, 5.0, int(2 * math.pi / N / 5.0))
    assert np.abs(_lvlh_angles(q[:, 0], t, u0)).max() < 1e-10
    np.testing.assert_allclose(w[:, 0], np.broadcast_to([0.0, 0.0, N], w[:, 0].shape), atol=1e-15)
    tau = np.asarray(plant.gravity_gradient_torque(jnp.asarray(t[-1]), jnp.asarray(q[-1])))
    assert np.abs(tau).max() < 1e-15


def test_lvlh_state_frame_flies_the_same_body():
    """The same tumbling body (full inertia) under gravity gradient integrated with the state relative to
    LVLH and with the inertial state: the inertial attitude and rate agree up to the RK4 error, which
    falls by more than 10x when dt halves (measured DCM difference 5.9e-9 over one orbit at dt = 2 s;
    rate 3.6e-12 rad/s), so the two formulations have the same solution; the
    LVLH-aligned principal body at rest relative to LVLH has zero state rates."""
    J = np.array([[10.0, 0.4, -0.2], [0.4, 20.0, 0.3], [-0.2, 0.3, 25.0]])
    u0 = 0.3
    q_i = np.array([0.2, -0.1, 0.3, 0.9])
    q_i /= np.linalg.norm(q_i)
    w_i = np.array([3 * N, -5 * N, 8 * N])
    inertial = _plant(J, w_i, q_i, u0=u0)
    # the same initial condition relative to LVLH (numpy): q_L = q_z(-u0) (x) q, w_r = omega - n o_b
    C = _dcm(q_i[None])[0]
    v, s4 = _rz(-u0)[:3], _rz(-u0)[3]
    q_l = np.concatenate(
        [s4 * q_i[:3] + q_i[3] * v + np.cross(v, q_i[:3]), [s4 * q_i[3] - v @ q_i[:3]]]
    )
    lvlh = _plant(J, w_i - N * C[2], q_l, u0=u0, frame="lvlh")
    diffs = []
    n_steps = int(2 * math.pi / N / 2.0)
    convert = jax.jit(jax.vmap(lambda tk, w, q: lvlh.inertial_and_lvlh(tk, {"omega": w, "q": q})))
    for dt in (
        2.0,
        1.0,
    ):  # one orbit, then half an orbit with the same number of steps (one compilation)
        t, w_a, q_a = _propagate(inertial, dt, n_steps)
        _, w_b, q_b = _propagate(lvlh, dt, n_steps)
        conv = convert(jnp.asarray(t), jnp.asarray(w_b), jnp.asarray(q_b))
        diffs.append(
            (
                np.abs(_dcm(np.asarray(conv[1])) - _dcm(q_a)).max(),
                np.abs(np.asarray(conv[0]) - w_a).max(),
            )
        )
    (dc2, dw2), (dc1, dw1) = diffs
    assert dc2 < 3e-8 and dw2 < 2e-11, diffs
    assert dc2 / dc1 > 10 and dw2 / dw1 > 10, diffs  # fourth order: 16
    rest = _plant(J, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0], u0=u0, frame="lvlh")
    J_diag = _plant(
        np.diag([10.0, 20.0, 25.0]), [0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0], frame="lvlh"
    )
    r = J_diag.rates(0.0, J_diag.initial_state(), jnp.zeros((1, 3)))
    assert np.abs(np.asarray(r["omega"])).max() < 1e-20 and np.abs(np.asarray(r["q"])).max() == 0.0
    # a non-principal body at rest relative to LVLH feels a gravity-gradient and gyroscopic torque
    assert (
        np.abs(np.asarray(rest.rates(0.0, rest.initial_state(), jnp.zeros((1, 3)))["omega"])).max()
        > 1e-9
    )


# ------------------------------------------------------------------------- composed plant type
def _raw(**plant):
    base = dict(
        type="attitude-truth",
        inertia=[10.0, 20.0, 25.0],
        initial_attitude_deg=[[0.0, 0.0, 0.0]] * 2,
    )
    base.update(plant)
    return {
        "scenario": {"name": "attitude-truth-test", "method": "composed"},
        "simulation": {"horizon": 1.0, "dt": 0.1, "record_every": 1, "seed": 1},
        "plant": base,
        "controller": {"type": "networked-el-hinf", "edges": [[1, 2]]},
        "sensors": {"type": "quaternion-euler"},
        "actuator": {"type": "euler-torque-allocation"},
    }


def test_lvlh_initial_frame_converts_to_inertial():
    scn = ftc.load_scenario(
        _raw(
            initial_frame="lvlh",
            initial_argument_of_latitude_deg=40.0,
            initial_attitude_deg=[[5.0, -3.0, 10.0], [0.0, 0.0, 0.0]],
            initial_body_rate=[[1e-3, 0.0, 0.0], [0.0, 0.0, 0.0]],
        )
    )
    sec = scn.section("plant")
    w, q = initial_inertial_state(sec)
    u0 = math.radians(40.0)
    Rz = np.array([[math.cos(u0), -math.sin(u0), 0], [math.sin(u0), math.cos(u0), 0], [0, 0, 1]])
    C_l = _dcm(sec.given_quaternions())
    np.testing.assert_allclose(_dcm(q), Rz @ C_l, atol=1e-14)  # C_BI = C_IL C_BL
    # omega = omega_rel + n (orbit normal in body axes) = omega_rel + n C_BL^T e_z
    np.testing.assert_allclose(
        w, np.array([[1e-3, 0, 0], [0, 0, 0]]) + N * C_l[:, 2, :], atol=1e-17
    )
    np.testing.assert_allclose(w[1], [0.0, 0.0, N], atol=1e-17)


def _euler_zyx(C):
    """[theta, phi, psi] of C = Rz(psi) Ry(theta) Rx(phi)."""
    return np.stack(
        [
            np.arctan2(-C[..., 2, 0], np.hypot(C[..., 2, 1], C[..., 2, 2])),
            np.arctan2(C[..., 2, 1], C[..., 2, 2]),
            np.arctan2(C[..., 1, 0], C[..., 0, 0]),
        ],
        axis=-1,
    )


@pytest.mark.parametrize("frame", ["inertial", "lvlh"])
def test_composed_run_records_gravity_gradient_and_usage(frame):
    """The Euler-angle law flies the plant with either state frame (initial attitude given in inertial
    axes); the law sees the attitude relative to that frame (its tracking error, desired 0, equals the
    3-2-1 angles of the recorded inertial or LVLH attitude); the recorded gravity-gradient torque equals
    an independent numpy value from the recorded quaternion and time; torque_impulse = int |command| dt
    (trapezoid on the records, the command being smooth); attitude_lvlh is Rz(u)^T C(q)."""
    raw = _raw(
        initial_attitude_deg=[[20.0, 10.0, -15.0], [-5.0, 30.0, 12.0]],
        initial_argument_of_latitude_deg=25.0,
        state_frame=frame,
    )
    raw["simulation"].update(horizon=2.0, dt=0.05, record_every=2)
    ds, _ = ftc.simulate_with_metrics(ftc.load_scenario(raw))
    t = ds.time.values
    q = ds.quaternion.values
    J = np.diag([10.0, 20.0, 25.0])
    u = math.radians(25.0) + N * t
    r_b = np.einsum("tnji,tj->tni", _dcm(q), np.stack([np.cos(u), np.sin(u), 0 * u], -1))
    tau = 3 * N**2 * np.cross(r_b, np.einsum("ij,tnj->tni", J, r_b))
    np.testing.assert_allclose(ds.gravity_gradient_torque.values, tau, rtol=1e-8, atol=1e-17)
    assert np.abs(tau).max() > 1e-6  # the torque acts here
    cmd = np.linalg.norm(ds.command.values, axis=-1)
    trap = np.concatenate(
        [
            np.zeros((1, cmd.shape[1])),
            np.cumsum(0.5 * (cmd[1:] + cmd[:-1]) * np.diff(t)[:, None], axis=0),
        ]
    )
    np.testing.assert_allclose(ds.torque_impulse.values, trap, rtol=2e-3, atol=1e-6)
    assert trap[-1].min() > 0.0
    C_bl = np.einsum(
        "tji,tnjk->tnik",
        np.stack(
            [
                np.stack([np.cos(u), -np.sin(u), 0 * u], -1),
                np.stack([np.sin(u), np.cos(u), 0 * u], -1),
                np.stack([0 * u, 0 * u, 1 + 0 * u], -1),
            ],
            -2,
        ),
        _dcm(q),
    )
    np.testing.assert_allclose(_dcm(ds.attitude_lvlh.values), C_bl, atol=1e-12)
    seen = C_bl if frame == "lvlh" else _dcm(q)
    np.testing.assert_allclose(ds.tracking_error.values, _euler_zyx(seen), atol=1e-10)
    # initial attitude: the given inertial 3-2-1 angles whatever the state frame
    np.testing.assert_allclose(
        _euler_zyx(_dcm(q[0])), np.radians([[20.0, 10.0, -15.0], [-5.0, 30.0, 12.0]]), atol=1e-12
    )


def test_builtin_scenario_validates():
    scn = ftc.load_scenario(SCENARIO)
    assert scn.type_of("plant") == "attitude-truth" and scn.section("plant").gravity_gradient
    assert scn.section("plant").semi_major_axis == 7.0e6


@pytest.mark.parametrize(
    "field, value, needle",
    [
        ("inertia", [10.0, -1.0, 25.0], "inertia"),
        ("semi_major_axis", 6.0e6, "plant.semi_major_axis"),
        ("mu", 0.0, "plant.mu"),
        ("inertia_matrices", [[[10.0, 1.0, 0.0], [0.0, 20.0, 0.0], [0.0, 0.0, 25.0]]], "symmetric"),
        ("inertia_matrices", [[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 5.0]]], "triangle"),
        ("initial_frame", "ecef", "plant.initial_frame"),
        ("state_frame", "body", "plant.state_frame"),
        ("gravity_gradiant", True, "plant.gravity_gradiant"),
    ],
)
def test_bad_section_is_rejected_naming_the_field(field, value, needle):
    with pytest.raises(ScenarioError, match=needle):
        ftc.load_scenario(_raw(**{field: value}))


def test_euler_law_on_attitude_truth_needs_the_euler_sensors():
    raw = _raw()
    del raw["sensors"]
    with pytest.raises(
        ScenarioError,
        match=r"controller networked-el-hinf needs 3-2-1 Euler angles and body rates.*"
        r'sensors type = "quaternion-euler" on a quaternion plant \("quaternion-rigid-body", '
        r'"attitude-truth"\)',
    ):
        ftc.load_scenario(raw)
