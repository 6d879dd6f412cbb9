"""End-to-end tests of the composed Mehrabian scenarios on shortened runs.

Truths: the energy balance d/dt(1/2 s^T D s) = s^T tau of the exact-model loop (passivity, E003-07) on
the simulated rigid-body plant; exact agreement of the in-run maxima with the every-step records;
rectangle-rule recomputation of the RK-integrated RMS metrics; convergence as dt -> 0; seed handling
(batched[i] == single run i, determinism, ranges of the drawn initial attitudes and inertias).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.api import build_loop, simulate_with_metrics
from formation_ftc.components.controllers.networked_el_hinf import synchronisation_torque
from formation_ftc.core import graph as graphs
from formation_ftc.core.dynamics.euler_lagrange import inertia_matrix
from formation_ftc.papers.mehrabian.seed_study import with_seed
from formation_ftc.sim.batch import batched_run, stack_params
from formation_ftc.sim.programs import jitted_run


def test_energy_balance_of_the_exact_model_loop():
    """No fault, no disturbance, true inertia = nominal: V = 1/2 sum s^T D s changes by int sum s^T tau dt.
    Trapezoid on the 0.01 s records: error O(dt^2 |V''| T) ~ 1e-6 relative to the total change."""
    s = ftc.load_scenario(
        "mehrabian-identification",
        {
            "actuator.faults": [],
            "estimator": None,
            "plant.disturbance_variance": 0.0,
            "plant.inertia_uncertainty": 0.0,
            "simulation.horizon": 20.0,
            "simulation.record_every": 1,
        },
    )
    ds, _ = simulate_with_metrics(s)
    q, sv = ds.attitude.values, ds.sliding_variable.values
    J = jnp.asarray(np.diag(s.section("plant").inertia))
    D = np.asarray(inertia_matrix(jnp.asarray(q), J))
    V = 0.5 * np.einsum("tjp,tjpq,tjq->t", sv, D, sv)
    m = 8
    A = graphs.adjacency(
        m, [(a - 1, b - 1) for a, b in s.section("controller").edges], directed=False
    )
    tau = np.asarray(
        synchronisation_torque(
            jnp.asarray(sv),
            jnp.asarray(graphs.row_normalized(A)),
            20.0 * jnp.ones((m, 3)),
            0.86 * jnp.ones(m),
            0.6 * jnp.ones(m),
        )
    )
    power = np.einsum("tjp,tjp->t", sv, tau)
    dt = 0.01
    work = np.concatenate([[0.0], np.cumsum(0.5 * dt * (power[1:] + power[:-1]))])
    change = V - V[0]
    assert abs(change[-1]) > 0.1  # a real transient (V(0) ~ 0.7 J)
    assert np.max(np.abs(change - work)) < 1e-4 * np.max(np.abs(change))


#: case 3 with the fault moved to [10, 40] s, 60 s, every step recorded; metric windows inside
SHORT_CASE_B = {
    "actuator.faults.0.start": 10.0,
    "actuator.faults.0.end": 40.0,
    "simulation.horizon": 60.0,
    "simulation.record_every": 1,
    "evaluations.0.fault_window": [10.0, 40.0],
    "evaluations.0.assessment_window": [15.0, 40.0],
}


@pytest.fixture(scope="module")
def short_case_b():
    """Case 3 on :data:`SHORT_CASE_B`."""
    s = ftc.load_scenario("mehrabian-identification", SHORT_CASE_B)
    ds, metrics = simulate_with_metrics(s)
    return s, ds, metrics


def test_fault_and_fdi_signals(short_case_b):
    s, ds, _ = short_case_b
    assert list(ds.axis.values) == ["pitch", "roll", "yaw"] and ds.attitude.attrs["units"] == "rad"
    t = ds.time.values
    on = (t >= 10.0 - 1e-9) & (t <= 40.0 + 1e-9)
    np.testing.assert_allclose(
        ds.fault.values[:, 0, 2], np.where(on, 0.05 * np.sin(0.02 * t) + 0.6, 0.0), atol=1e-12
    )
    on_d = (t >= 15.0 - 1e-9) & (t <= 45.0 + 1e-9)
    np.testing.assert_allclose(
        ds.fdi_estimate.values[:, 0, 2],
        np.where(on_d, 0.05 * np.sin(0.02 * (t - 5.0)) + 0.5, 0.0),
        atol=1e-12,
    )
    assert np.all(ds.fault_estimate_adaptive.values[t < 15.0 - 1e-9] == 0.0)
    assert ds.fault_estimate_adaptive.values[-1, 0, 2] != 0.0
    assert np.all(ds.fault_estimate_adaptive.values[:, 1:] == 0.0)


def test_metrics_agree_with_records(short_case_b):
    """Maxima: exactly the max over the recorded steps k0 <= k < k1. RMS and effort: the in-run RK
    integrals vs a rectangle rule on the 0.01 s records, 1 % (first-order quadrature difference)."""
    s, ds, m = short_case_b
    q = ds.attitude.values
    edges = s.section("controller").edges
    A = graphs.adjacency(8, [(a - 1, b - 1) for a, b in edges], directed=False)
    j, n = np.nonzero(np.triu(A > 0, 1))  # each undirected link once
    assert list(ds.link.values) == [f"{a + 1}-{b + 1}" for a, b in zip(j, n, strict=True)]
    k0, k1 = 1000, 4000
    pair = np.linalg.norm(q[:, j] - q[:, n], axis=-1)
    assert m["sync_err_max_fault_window"] == pytest.approx(pair[k0:k1].max(), abs=1e-14)
    assert m["track_err_max_fault_window"] == pytest.approx(
        np.linalg.norm(q, axis=-1)[k0:k1].max(), abs=1e-14
    )
    assert m["spread_max_yaw_fault_window"] == pytest.approx(
        np.ptp(q[k0:k1, :, 2], axis=1).max(), abs=1e-14
    )
    assert m["abs_max_pitch_run"] == pytest.approx(np.abs(q[:6000, :, 0]).max(), abs=1e-14)
    rms = np.sqrt(np.mean(np.mean(pair[k0:k1] ** 2, axis=1)))
    assert m["sync_err_rms_fault_window"] == pytest.approx(rms, rel=1e-2)
    trk = np.sqrt(np.mean(np.mean(np.sum(q[k0:k1] ** 2, -1), axis=1)))
    assert m["track_err_rms_fault_window"] == pytest.approx(trk, rel=1e-2)
    eff = np.sum(ds.command.values[k0:k1] ** 2) * 0.01
    assert m["control_effort_fault_window"] == pytest.approx(eff, rel=1e-2)
    assert m["sync_err_rms_run"] > 0 and np.isfinite(list(m.values())).all()


def test_converges_as_dt_shrinks():
    """Continuous-time law evaluated at the RK stages: the 25 s attitude (fault active from 5 s,
    reconfiguration from 10 s) changes by less between dt = 0.01 and 0.005 than between 0.02 and 0.005,
    and by < 1e-4 rad (sat/sign terms make RK4 roughly first order, PERFORMANCE.md)."""
    finals = {}
    for dt in (0.02, 0.01, 0.005):
        s = ftc.load_scenario(
            "mehrabian-identification",
            {
                "actuator.faults.0.start": 5.0,
                "simulation.horizon": 25.0,
                "simulation.dt": dt,
                "simulation.record_every": round(25.0 / dt),
                "plant.disturbance_variance": 0.0,
                "evaluations.0.fault_window": [5.0, 25.0],
                "evaluations.0.assessment_window": [10.0, 25.0],
            },
        )
        c = build_loop(s)
        finals[dt] = np.asarray(jax.jit(type(c).run)(c)["final"]["plant"]["q"])
    e1 = np.abs(finals[0.02] - finals[0.005]).max()
    e2 = np.abs(finals[0.01] - finals[0.005]).max()
    assert e2 < e1 and e2 < 1e-4


#: case 2 on 20 s recorded every 1 s: the structure of the isolation tests below, one program for them
ISOLATION_SHORT = {"simulation.horizon": 20.0, "simulation.record_every": 100}


def test_seeds_batched_equals_single_and_draws():
    s = ftc.load_scenario("mehrabian-isolation", ISOLATION_SHORT)
    c = build_loop(s)
    seeds = [1, 2, 7]
    P, axes = stack_params([with_seed(c, sd) for sd in seeds])
    batched = batched_run(c, axes, len(seeds))(P)
    single = jitted_run(c)  # the program simulate_with_metrics runs this structure with
    q0, finals = [], []
    for i, seed in enumerate(seeds):
        one = single(with_seed(c, seed))
        # batched[i] == single run i (to the last bits: shared leaves compile to another program)
        np.testing.assert_allclose(
            np.asarray(batched["final"]["plant"]["q"][i]),
            np.asarray(one["final"]["plant"]["q"]),
            rtol=0,
            atol=1e-12,
        )
        q0.append(np.asarray(one["records"]["attitude"][0]))
        finals.append(np.asarray(one["final"]["plant"]["q"]))
    again = single(with_seed(c, 1))  # deterministic in the seed
    np.testing.assert_array_equal(np.asarray(again["final"]["plant"]["q"]), finals[0])
    q0 = np.rad2deg(np.stack(q0))
    assert q0.min() >= 0.0 and q0.max() <= 60.0 and q0.std() > 10.0
    assert not np.allclose(q0[0], q0[1])
    # drawn inertia: J = J^ diag(1 + delta), |delta| <= 0.1 (inspect the setup through the step's effect)
    from formation_ftc.core.disturbances import run_key

    k_q0, k_J, _, _ = jax.random.split(run_key(jnp.asarray(1, dtype=jnp.uint32)), 4)
    delta = 0.1 * np.asarray(
        jax.random.uniform(k_J, (8, 3), dtype=jnp.float64, minval=-1.0, maxval=1.0)
    )
    assert np.abs(delta).max() <= 0.1 and np.abs(delta).max() > 0.05
    np.testing.assert_allclose(
        q0[0],
        np.rad2deg(
            np.asarray(
                jax.random.uniform(
                    k_q0, (8, 3), dtype=jnp.float64, minval=0.0, maxval=np.deg2rad(60.0)
                )
            )
        ),
        atol=1e-12,
    )


def test_disturbance_statistics(short_case_b):
    """d ~ N(0, 0.001) i.i.d.: 6,001 steps x 24 channels; sample variance within 3 % (std error 0.4 %),
    mean within 4 standard errors, lag-1 correlation between steps < 0.02 (fresh sample each step)."""
    _, ds, _ = short_case_b
    d = ds.disturbance.values
    assert abs(d.var() / 0.001 - 1.0) < 0.03
    assert abs(d.mean()) < 4 * np.sqrt(0.001 / d.size)
    x = d.reshape(d.shape[0], -1)
    r1 = np.mean(x[1:] * x[:-1]) / d.var()
    assert abs(r1) < 0.02


def test_paper_figures(short_case_b, tmp_path):
    """``[scenario] paper = "mehrabian"``: the composed method draws the paper's figures."""
    from formation_ftc.registry import get_method

    s, ds, _ = short_case_b
    paths = get_method("composed").plot(ds, s, tmp_path)
    assert [p.name for p in paths] == ["attitudes.png", "fault_estimate.png"]
    assert all(p.stat().st_size > 10_000 for p in paths)


def test_wrong_spacecraft_isolation_reconfigures_the_healthy_one():
    s = ftc.load_scenario(
        "mehrabian-isolation",
        {
            "estimator.isolation.0.reported_spacecraft": 2,
            "estimator.isolation.0.reported_channel": 3,
            "actuator.faults.0.start": 5.0,
            **ISOLATION_SHORT,
        },
    )
    ds, _ = simulate_with_metrics(s)
    flag, u_hat = ds.fdi_flag.values, ds.fault_estimate_adaptive.values
    t = ds.time.values
    np.testing.assert_array_equal(flag[:, 1, 2], (t >= 10.0 - 1e-9).astype(float))
    assert flag.sum() == flag[:, 1, 2].sum()
    assert np.all(u_hat[:, 0] == 0.0) and u_hat[-1, 1, 2] != 0.0
    np.testing.assert_allclose(
        ds.fdi_estimate.values[-1, 1, 2], 0.05 * np.sin(0.02 * 15.0) + 0.5, atol=1e-12
    )


def test_euler_pitch_bound_names_the_singular_angle():
    """Mehrabian's plant holds 3-2-1 Euler angles (singular at pitch +-pi/2): its initial pitches lie in
    [0, 60] deg, so a 0.3 rad bound is left at once and the diagnostic names the pitch."""
    # on the short case's program (the bound is a leaf)
    scn = ftc.load_scenario(
        "mehrabian-identification", {**SHORT_CASE_B, "simulation.max_pitch": 0.3}
    )
    with pytest.raises(ftc.SimulationDiverged) as err:
        ftc.simulate(scn)
    assert err.value.info.variable.startswith("plant.pitch")
    with pytest.raises(ValueError, match="max_pitch"):
        ftc.load_scenario("mehrabian-identification", {"simulation.max_pitch": 1.6})
