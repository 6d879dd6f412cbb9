"""LQR formation controller (composed type ``lqr``): the law against a numpy evaluation of its
formula, the closed-loop error on the CW plant against the matrix exponential of A - B K (continuous)
and the ZOH recursion (sampled), the decay rate against the slowest closed-loop eigenvalue, the flight /
truth boundary, and rejection of bad sections."""

from __future__ import annotations

import dataclasses
import inspect
import math
import typing

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg

import formation_ftc as ftc
from formation_ftc.components.controllers.lqr import LqrFormationController
from formation_ftc.config.loader import ScenarioError
from formation_ftc.core.dynamics.cw import cw_matrices
from formation_ftc.core.orbit import MU_EARTH
from formation_ftc.design.lqr import cw_lqr
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import FlightInputs

A_ORBIT = 7000e3
N = math.sqrt(MU_EARTH / A_ORBIT**3)
MASS = [100.0, 120.0]
# per-axis Bryson weights: slowest closed-loop mode ~ -0.025 1/s (z), well apart from the others
BRYSON = {
    "max_position_error": [10.0, 20.0, 40.0],
    "max_velocity_error": 1.0,
    "max_acceleration": 1.0,
}


def _raw(desired, *, mode="continuous", horizon=250.0, dt=0.1, controller=None, **slots):
    raw = {
        "scenario": {"name": "lqr-test", "method": "composed"},
        "simulation": {"horizon": horizon, "dt": dt, "record_every": 10},
        "plant": {
            "type": "clohessy-wiltshire",
            "semi_major_axis": A_ORBIT,
            "mass": MASS,
            "initial_position": [[30.0, -20.0, 15.0], [-10.0, 40.0, -25.0]],
            "initial_velocity": [[0.1, 0.0, -0.05], [0.0, -0.2, 0.1]],
        },
        "controller": {
            "type": "lqr",
            "semi_major_axis": A_ORBIT,
            "nominal_mass": MASS,  # the law's stated masses, here the true ones
            **BRYSON,
            "desired_position": desired,
            "mode": mode,
            **(controller or {}),
        },
    }
    raw.update(slots)
    return raw


def _desired_numpy(t, i, moving):
    """q^d(t) of the expressions below for spacecraft i (1-based), written out by hand [m, m/s]."""
    if not moving:
        return np.array([50.0 * i, -100.0, 20.0, 0.0, 0.0, 0.0])
    w = 0.01
    return np.array(
        [
            50.0 * i + 20 * np.sin(w * t),
            -100.0 + 5 * t,
            20.0 * np.cos(w * t),
            20 * w * np.cos(w * t),
            5.0,
            -20.0 * w * np.sin(w * t),
        ]
    )


FIXED = ["50*i", "-100", "20"]
MOVING = ["50*i + 20*sin(0.01*t)", "-100 + 5*t", "20*cos(0.01*t)"]


def test_output_equals_the_formula():
    """u_i = m_i (-K (y_i - q_i^d) - (A q_i^d)[3:] + a_i^d) with A from ``cw_matrices`` (numpy)."""
    loop = make_loop(ftc.load_scenario(_raw(MOVING)))
    law = loop.controller
    assert isinstance(law, LqrFormationController)
    t = 37.0
    y = np.random.default_rng(3).normal(size=(2, 6)) * [50, 50, 50, 1, 1, 1]
    inputs = FlightInputs(
        measurement=jnp.asarray(y),
        received=None,
        estimate=None,
        decision=None,
        exogenous=law.exogenous(jnp.asarray(t)),
        reference=None,
        step=None,
    )
    u, _, _ = law.output(jnp.asarray(t), None, inputs)
    A, _ = cw_matrices(N)
    K = cw_lqr(N, **BRYSON).K
    w = 0.01
    expected = []
    for i in (1, 2):
        qd = _desired_numpy(t, i, True)
        ad = np.array([-20 * w**2 * np.sin(w * t), 0.0, -20 * w**2 * np.cos(w * t)])
        expected.append(MASS[i - 1] * (-K @ (y[i - 1] - qd) - (A @ qd)[3:] + ad))
    np.testing.assert_allclose(np.asarray(u), np.array(expected), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("desired, moving", [(FIXED, False), (MOVING, True)])
def test_continuous_error_follows_expm_and_decays_at_the_slowest_eigenvalue(desired, moving):
    """On the CW plant the error obeys e_dot = (A - B K) e (the feed-forward makes any desired
    trajectory an equilibrium): e(t) = expm((A - B K) t) e(0) (scipy), up to RK4's error; the fitted
    decay rate of |e| after the fast modes have died equals the slowest eigenvalue's real part."""
    ds = ftc.simulate(ftc.load_scenario(_raw(desired, horizon=400.0)))
    A, B = cw_matrices(N)
    d = cw_lqr(N, **BRYSON)
    Acl = A - B @ d.K
    q0 = np.array([[30.0, -20.0, 15.0, 0.1, 0.0, -0.05], [-10.0, 40.0, -25.0, 0.0, -0.2, 0.1]])
    t = ds.time.values
    for i in range(2):
        e0 = q0[i] - _desired_numpy(0.0, i + 1, moving)
        e = np.stack([scipy.linalg.expm(Acl * tk) @ e0 for tk in t])
        np.testing.assert_allclose(
            ds.position_error.values[:, i], e[:, :3], rtol=0, atol=1e-6 * np.abs(e0).max()
        )
    # decay rate: least-squares slope of log |e| over [150, 400] s, where the slowest mode (z axis,
    # ~ -0.025 1/s) dominates the next one (y axis, ~ -0.05 1/s) by e^(-0.025 * 150) < 3 %
    sigma = np.max(np.linalg.eigvals(Acl).real)
    window = t >= 150.0
    for i in range(2):
        en = np.linalg.norm(ds.position_error.values[window, i], axis=-1)
        slope = np.polyfit(t[window], np.log(en), 1)[0]
        assert slope == pytest.approx(sigma, rel=0.01), (slope, sigma)


def test_sampled_mode_follows_the_zoh_recursion():
    """mode = "sampled" with fixed offsets: the command is held over each step, so the error obeys the
    exact ZOH recursion e_{k+1} = (Phi - Gamma K) e_k, Phi = expm(A dt), Gamma = int_0^dt expm(A s) ds B."""
    dt = 0.5
    ds = ftc.simulate(ftc.load_scenario(_raw(FIXED, mode="sampled", horizon=100.0, dt=dt)))
    A, B = cw_matrices(N)
    K = cw_lqr(N, **BRYSON).K
    M = scipy.linalg.expm(
        np.block([[A, B], [np.zeros((3, 9))]]) * dt
    )  # Van Loan: [[Phi, Gamma], [0, I]]
    Phi, Gam = M[:6, :6], M[:6, 6:]
    F = Phi - Gam @ K
    q0 = np.array([[30.0, -20.0, 15.0, 0.1, 0.0, -0.05], [-10.0, 40.0, -25.0, 0.0, -0.2, 0.1]])
    steps = np.rint(ds.time.values / dt).astype(int)
    for i in range(2):
        e = q0[i] - _desired_numpy(0.0, i + 1, False)
        traj = [e]
        for _ in range(steps[-1]):
            traj.append(F @ traj[-1])
        np.testing.assert_allclose(
            ds.position_error.values[:, i], np.array(traj)[steps, :3], rtol=0, atol=1e-7
        )
    # and it is not the continuous law: the held command differs from the continuous one
    dc = ftc.simulate(ftc.load_scenario(_raw(FIXED, horizon=100.0, dt=dt)))
    assert np.max(np.abs(dc.position_error.values - ds.position_error.values)) > 1e-3


def test_controller_cannot_see_the_truth():
    """With identical flight inputs the command is unchanged when the plant's masses and disturbance
    and the actuator's faults change, while the applied force does change."""
    hints = typing.get_type_hints(
        LqrFormationController.output,
        globalns=vars(inspect.getmodule(LqrFormationController)) | {"FlightInputs": FlightInputs},
    )
    assert hints["inputs"] is FlightInputs
    loop = make_loop(
        ftc.load_scenario(
            "compose-lqr-on-cw", {"simulation.horizon": 1.0, "simulation.record_every": 1}
        )
    )
    assert isinstance(loop.controller, LqrFormationController)
    act = dataclasses.replace(
        loop.actuator, onset=loop.actuator.onset * 0.0, magnitude=loop.actuator.magnitude + 3.0
    )
    plant = dataclasses.replace(
        loop.plant, mass=loop.plant.mass * 1.7, disturbance_force=("5", "5*t", "-5")
    )
    other = dataclasses.replace(loop, actuator=act, plant=plant)
    k = jnp.asarray(3, dtype=jnp.int64)
    state = loop.initial_state()
    step = jax.jit(lambda lp, st: lp.step(k, st)[1])
    out_a, out_b = step(loop, state), step(other, state)
    np.testing.assert_array_equal(np.asarray(out_a["command"]), np.asarray(out_b["command"]))
    assert np.max(np.abs(np.asarray(out_a["applied"]) - np.asarray(out_b["applied"]))) > 1e-3


def test_builtin_scenario_reaches_the_steady_offset_of_a_constant_fault():
    """compose-lqr-on-cw: before the faults (t < 1500 s) the formation error is small; under the 0.5 m/s^2
    x-axis bias the LQR (no integral action) settles at the offset e = -(A - B K)^-1 B f of the CW model."""
    ds = ftc.simulate(ftc.load_scenario("compose-lqr-on-cw", {"simulation.horizon": 1990.0}))
    e = ds.position_error.values
    t = ds.time.values
    assert np.max(np.linalg.norm(e[(t > 500) & (t < 1500)], axis=-1)) < 0.2
    A, B = cw_matrices(N)
    K = cw_lqr(N, 10.0, 1.0, 1.0).K
    e_ss = -np.linalg.solve(A - B @ K, B @ np.array([0.5, 0.0, 0.0]))[:3]
    assert np.linalg.norm(e_ss) > 4.0  # an honest non-FTC baseline: the fault is not rejected
    np.testing.assert_allclose(e[-1], np.broadcast_to(e_ss, e[-1].shape), atol=0.2)


@pytest.mark.parametrize(
    "controller, slots, needle",
    [
        ({"max_position_error": 0.0}, {}, "controller.max_position_error"),
        ({"max_acceleration": [1.0, 2.0]}, {}, "controller.max_acceleration"),
        ({"max_velocity_error": -1.0}, {}, "controller.max_velocity_error"),
        ({"nominal_mass": [1.0, 2.0, 3.0]}, {}, "controller.nominal_mass"),
        ({"nominal_mass": -5.0}, {}, "controller.nominal_mass"),
        ({"kp": 1.0}, {}, "controller.kp"),
        ({"mode": "hybrid"}, {}, "controller.mode"),
        ({"semi_major_axis": -1.0}, {}, "controller.semi_major_axis"),
        (
            {},
            {
                "network": {
                    "type": "delayed-graph",
                    "adjacency": [[0, 1], [1, 0]],
                    "delays": [["1", "1"], ["1", "1"]],
                    "max_delay": 1.0,
                }
            },
            "network delayed-graph delays messages, but controller lqr exchanges none",
        ),
    ],
)
def test_bad_sections_are_rejected(controller, slots, needle):
    with pytest.raises(ScenarioError) as err:
        ftc.load_scenario(_raw(FIXED, controller=controller, **slots))
    assert needle in str(err.value)
