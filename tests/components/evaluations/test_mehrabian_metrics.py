"""Evaluation ``mehrabian-metrics``: its metric set and windows, the loop's refusal without the law and
the plant it scores, and the reductions it uses (stage integrals, component / square / range) against
closed forms."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components.controllers.none import ZeroController
from formation_ftc.components.evaluations.mehrabian_metrics import metric_windows
from formation_ftc.components.plants.clohessy_wiltshire import ClohessyWiltshirePlant
from formation_ftc.config.loader import ScenarioError
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.loop import ClosedLoop
from formation_ftc.sim.metrics import Metric, finalize, init_accumulators, update_stage_accumulators


def test_metric_set_and_windows_clipped_to_the_horizon():
    """Every window gives the 12 metrics (6 error and effort, 3 spreads, 3 largest angles); a window clipped to the horizon keeps its start, one that
    starts after it gives none."""
    scenario = ftc.load_scenario("mehrabian-identification", {"simulation.horizon": 42.0})
    windows = metric_windows(scenario)
    assert windows == {
        "fault_window": (40.0, 42.0),
        "run": (0.0, 42.0),
        "assessment_window": (42.0, 42.0),
    }
    names = [m.name for m in make_loop(scenario).metrics]
    assert len([n for n in names if n.endswith("_fault_window")]) == 12
    assert len([n for n in names if n.endswith("_run")]) == 12
    assert not [n for n in names if n.endswith("_assessment_window")]
    assert "spread_max_yaw_run" in names and "sync_err_rms_fault_window" in names


def test_needs_the_euler_angle_law_and_plant():
    """On the quaternion plant the metrics have no Euler-angle plant to score: the loop is refused,
    naming the evaluation and who would provide what it needs."""
    raw = {
        "scenario": {"name": "t", "method": "composed"},
        "simulation": {"horizon": 1.0, "dt": 0.01},
        "plant": {
            "type": "quaternion-rigid-body",
            "inertia": [20.0, 18.0, 15.0],
            "initial_attitude_deg": [[10.0, 0.0, 0.0], [0.0, 20.0, 0.0]],
        },
        "sensors": {"type": "quaternion-euler"},
        "controller": {"type": "networked-el-hinf", "edges": [[1, 2]]},
        "actuator": {"type": "euler-torque-allocation"},
        "evaluations": [{"type": "mehrabian-metrics"}],
    }
    with pytest.raises(ScenarioError) as err:
        ftc.load_scenario(raw)
    msg = str(err.value)
    assert "evaluations[0] mehrabian-metrics needs" in msg and "euler-angle-attitude" in msg


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
