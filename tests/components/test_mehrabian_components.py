"""mehrabian components: the controller and the FDI cannot see the truth; plant, fault actuator and
FDI report against independent formulas; the sample-and-hold time signals and the stage-integrated
metric reductions of the closed loop."""

from __future__ import annotations

import dataclasses
import inspect
import typing

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components.actuators.additive_faults import HeldAdditiveFaultActuator
from formation_ftc.components.controllers.networked_el_hinf import NetworkedElHinfController
from formation_ftc.components.controllers.none import ZeroController
from formation_ftc.components.estimators.fdi_imperfections import ScriptedFdi
from formation_ftc.components.plants.clohessy_wiltshire import ClohessyWiltshirePlant
from formation_ftc.core.dynamics.euler_lagrange import rigid_body_rhs
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import FlightInputs, TruthInputs
from formation_ftc.sim.loop import ClosedLoop
from formation_ftc.sim.metrics import Metric, finalize, init_accumulators, update_stage_accumulators

TRUTH_FIELDS = {"state", "true_state", "fault", "faults", "disturbance", "force", "process_noise"}


def _loop(name="mehrabian-identification", **ov):
    return make_loop(
        ftc.load_scenario(name, {"simulation.horizon": 1.0, "simulation.record_every": 1, **ov})
    )


def _hints(cls, meth):
    mod = vars(inspect.getmodule(cls)) | {"FlightInputs": FlightInputs}
    return typing.get_type_hints(getattr(cls, meth), globalns=mod)


def test_controller_and_fdi_cannot_see_the_truth():
    """Controller and FDI read FlightInputs only (no truth field); with the same flight inputs the
    command and the FDI report are unchanged when the true fault, the disturbance and the true inertia
    change, while the applied torque changes."""
    assert _hints(NetworkedElHinfController, "output")["inputs"] is FlightInputs
    assert _hints(ScriptedFdi, "update")["inputs"] is FlightInputs
    assert not TRUTH_FIELDS & set(FlightInputs._fields)
    # fault active from t = 0 and the FDI reporting from 0 s (no latency)
    loop = _loop(**{"actuator.faults.0.start": 0.0, "estimator.delay": 0.0})
    assert isinstance(loop.controller, NetworkedElHinfController) and isinstance(
        loop.estimator, ScriptedFdi
    )
    assert isinstance(loop.actuator, HeldAdditiveFaultActuator)
    act = dataclasses.replace(
        loop.actuator, torques=("3*sin(t) - 2",), windows=loop.actuator.windows + 0.0
    )
    plant = dataclasses.replace(
        loop.plant,
        disturbance_std=loop.plant.disturbance_std * 50.0,
        inertia_spread=loop.plant.inertia_spread * 0.1,
    )
    other = dataclasses.replace(loop, actuator=act, plant=plant)
    k = jnp.asarray(3, dtype=jnp.int64)
    state = loop.initial_state()  # same true state (same seed), hence the same measurement
    step = jax.jit(lambda lp, st: lp.prepared().step(k, st)[1])
    a, b = step(loop, state), step(other, state)
    for name in ("command", "fdi_flag", "fdi_estimate", "sliding_variable"):
        np.testing.assert_array_equal(np.asarray(a[name]), np.asarray(b[name]))
    assert np.max(np.abs(np.asarray(a["applied"]) - np.asarray(b["applied"]))) > 1.0
    assert np.asarray(a["fdi_flag"])[0, 2] == 1.0


def test_plant_equals_the_rigid_body_model():
    """Derivative = Euler's equation with the drawn inertia J = J^ diag(1 + delta), |delta| <= 0.1, and
    the held disturbance added to the generalised torque."""
    loop = _loop()
    plant = loop.plant.prepare(loop.dt)
    J = np.asarray(plant.J)
    delta = np.diagonal(J, axis1=1, axis2=2) / np.array([20.0, 18.0, 15.0]) - 1.0
    assert np.all(np.abs(delta) <= 0.1) and np.abs(delta).max() > 0.05
    np.testing.assert_allclose(J - np.stack([np.diag(np.diagonal(j)) for j in J]), 0.0, atol=0)
    x = plant.initial_state()
    rng = np.random.default_rng(1)
    x = {"q": x["q"], "w": jnp.asarray(rng.normal(size=(8, 3)) * 0.01)}
    u = jnp.asarray(rng.normal(size=(8, 3)))
    exo = plant.exogenous(jnp.asarray(0.25))
    dx = plant.derivative(0.25, x, TruthInputs(u, exo, None, None))
    q_dot, w_dot = rigid_body_rhs(x["q"], x["w"], u + exo["d"], jnp.asarray(J), jnp.linalg.inv(J))
    np.testing.assert_allclose(np.asarray(dx["q"]), np.asarray(q_dot), rtol=1e-14)
    np.testing.assert_allclose(np.asarray(dx["w"]), np.asarray(w_dot), rtol=1e-12, atol=1e-18)
    # the disturbance of step 25 is a fresh N(0, 0.001) sample, different from step 26's
    d25, d26 = (np.asarray(plant.exogenous(jnp.asarray(k * 0.01))["d"]) for k in (25, 26))
    assert not np.allclose(d25, d26) and 0.005 < d25.std() < 0.08


def test_held_time_signals_and_fault_and_fdi_profiles():
    """The fault (2) is 0.05 sin(0.02 t_k) + 0.6 on the snapped window, held over the step (the same
    value at the three stage times); the FDI reports u* = u_bar(t - 5) - 0.1 and the flag from 45 s."""
    loop = _loop(**{"simulation.horizon": 300.0})
    assert loop.actuator.holds_exogenous and loop.plant.holds_exogenous
    for k in (3999, 4000, 12345, 24000, 24001):
        t_k = k * 0.01
        table = loop._time_table(jnp.asarray(t_k))
        f = np.asarray(table["actuator"]["fault"])
        want = 0.05 * np.sin(0.02 * t_k) + 0.6 if 4000 <= k <= 24000 else 0.0
        assert f.shape == (3, 8, 3)
        np.testing.assert_allclose(f[:, 0, 2], want, rtol=1e-15, atol=0)
        assert np.count_nonzero(f[:, 1:]) == 0 and np.count_nonzero(f[:, 0, :2]) == 0
        d = np.asarray(table["plant"]["d"])
        np.testing.assert_array_equal(d[0], d[2])
        _, rep = loop.estimator.update(
            jnp.asarray(t_k), None, FlightInputs(*[None] * 6, loop._step_context(jnp.asarray(k)))
        )
        flag, est = np.asarray(rep.flag), np.asarray(rep.estimate)
        on = k >= 4500
        assert flag[0, 2] == float(on) and flag.sum() == float(on)
        tw = t_k - 5.0
        seen = 4000 <= k - 500 <= 24000
        np.testing.assert_allclose(
            est[0, 2],
            (0.05 * np.sin(0.02 * tw) + 0.5) if on and seen else 0.0,
            rtol=1e-14,
            atol=1e-15,
        )


def _cw_loop(metrics, dt=1.0, n=600):
    n_mm = 0.0011
    plant = ClohessyWiltshirePlant(
        mean_motion=jnp.asarray(n_mm),
        mass=jnp.asarray([100.0]),
        initial_state_lvlh=jnp.asarray([[50.0, 0.0, 0.0, 0.0, 0.0, 0.0]]),
    )
    return ClosedLoop(
        plant=plant,
        controller=ZeroController(count=1),
        metrics=tuple(metrics),
        dt=dt,
        n_steps=n,
        record_every=n,
    )


def test_stage_integral_is_the_rk4_quadrature():
    """Free CW drift from x0 = 50 m: x(t) = x0 (4 - 3 cos nt), so int_a^b x dt =
    x0 (4 (b - a) - 3 (sin nb - sin na) / n). The stage-integrated metric matches it to 1e-10 (RK4
    quadrature), the rectangle-rule ``integral`` only to O(dt); ``stage_root_mean`` of x^2 is the RMS."""
    n_mm, x0 = 0.0011, 50.0
    a, b = 100.0, 500.0
    mets = [
        Metric("si", "position", "stage_integral", component=0, spacecraft="sum", start=a, end=b),
        Metric("rect", "position", "integral", component=0, spacecraft="sum", start=a, end=b - 0.5),
        Metric(
            "rms",
            "position",
            "stage_root_mean",
            component=0,
            square=True,
            spacecraft="sum",
            start=a,
            end=b,
        ),
    ]
    out = jax.jit(lambda lp: lp.run()["metrics"])(_cw_loop(mets))
    si, rect, rms = (float(v) for v in out)
    want = x0 * (4 * (b - a) - 3 * (np.sin(n_mm * b) - np.sin(n_mm * a)) / n_mm)
    assert si == pytest.approx(want, rel=1e-10)
    assert abs(rect - want) > 1e-6 * abs(want)  # the sample rule is not the quadrature
    # int x^2 = x0^2 int (16 - 24 cos + 9 cos^2)
    t = np.linspace(a, b, 400001)
    x = x0 * (4 - 3 * np.cos(n_mm * t))
    assert rms == pytest.approx(np.sqrt(np.trapezoid(x**2, t) / (b - a)), rel=1e-9)


def test_metric_component_square_and_range_options():
    """component / square / spacecraft = "range" against numpy; stage accumulators count whole steps
    inside the window only."""
    rng = np.random.default_rng(3)
    v = rng.normal(size=(5, 3))
    sig = {"s": jnp.asarray(v)}
    cases = [
        (Metric("a", "s", component=1, spacecraft="range"), np.ptp(v[:, 1])),
        (Metric("b", "s", component=2, norm=True, spacecraft="max"), np.abs(v[:, 2]).max()),
        (Metric("c", "s", norm=True, square=True, spacecraft="mean"), np.mean(np.sum(v**2, -1))),
        (Metric("d", "s", square=True, component=0, spacecraft="sum"), np.sum(v[:, 0] ** 2)),
    ]
    for m, want in cases:
        assert float(m.value(sig)) == pytest.approx(want, rel=1e-14)
    m = Metric(
        "e", "s", "stage_integral", norm=True, square=True, spacecraft="sum", start=1.0, end=3.0
    )
    acc = init_accumulators([m], sig)
    for k in range(5):  # steps [k, k + 1]: only k = 1, 2 lie inside [1, 3]
        acc = update_stage_accumulators(
            [m], acc, jnp.asarray(float(k)), 1.0, (jnp.asarray(10.0**k),)
        )
    assert float(finalize([m], acc)[0]) == 110.0
