"""Estimator ``scripted-fdi`` (formation_ftc.components.estimators.scripted_fdi).

Truths: the closed-form FDI estimate of SPEC P3.4 / E003-10 (u* = u_bar(t - 5) - 0.1 on [45, 245] s,
0 elsewhere), exact routing of isolation errors, the sample statistics of the identification noise, the
kernel conformance rules (float64, jit, vmap batched[i] == single i, determinism under a key), the held
fault and report of a Mehrabian scenario, and the loop's refusal without the actuator's faults.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components.estimators.scripted_fdi import (
    FDIModel,
    fdi_output,
    fdi_params,
    identity_routing,
    isolation_routing,
)
from formation_ftc.config.loader import ScenarioError
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import FlightInputs

M, K, DT = 8, 3, 0.01


def paper_fault(k):
    """u_bar_{1,3}(t) = 0.05 sin(0.02 t) + 0.6 on 40 <= t <= 240 s (Mehrabian Sec. V), by step index."""
    t = k * DT
    on = (k >= 4000) & (k <= 24000)
    return jnp.zeros((M, K)).at[0, 2].set(jnp.where(on, 0.05 * jnp.sin(0.02 * t) + 0.6, 0.0))


MODEL = FDIModel(M, K, paper_fault, DT)
MASK = np.zeros((M, K))
MASK[0, 2] = 1.0
KEY = jax.random.PRNGKey(0)


def outputs(params, ks, key=KEY):
    f = jax.jit(jax.vmap(lambda k: fdi_output(MODEL, params, k, jax.random.fold_in(key, k))))
    out = f(jnp.asarray(ks))
    return np.asarray(out.flag), np.asarray(out.estimate)


def test_spec_identification_estimate_closed_form():
    p = fdi_params(M, K, fault_mask=MASK, onset=40.0, delay=5.0, scale=1.0, bias=-0.1)
    ks = np.arange(0, 30001, 7)
    flag, est = outputs(p, ks)
    t = ks * DT
    want = np.where(
        (t >= 45.0 - 1e-9) & (t <= 245.0 + 1e-9), 0.05 * np.sin(0.02 * (t - 5.0)) + 0.5, 0.0
    )
    np.testing.assert_allclose(est[:, 0, 2], want, atol=1e-12)
    # every other channel reports nothing; the flag is latched from 45 s (also after 245 s)
    others = est.copy()
    others[:, 0, 2] = 0.0
    assert np.all(others == 0.0)
    np.testing.assert_array_equal(flag[:, 0, 2], (ks >= 4500).astype(float))
    assert flag.sum(axis=(1, 2)).max() == 1.0


def test_missed_detection_reports_nothing():
    p = fdi_params(M, K, fault_mask=MASK, onset=40.0, delay=5.0, detected=False)
    flag, est = outputs(p, np.arange(0, 30001, 100))
    assert np.all(flag == 0.0) and np.all(est == 0.0)


@pytest.mark.parametrize("target", [(0, 1), (3, 2)], ids=["wrong-channel", "wrong-spacecraft"])
def test_isolation_error_moves_flag_and_estimate(target):
    R = isolation_routing(M, K, {(0, 2): target})
    p = fdi_params(M, K, fault_mask=MASK, onset=40.0, delay=5.0, bias=-0.1, routing=R)
    p_ok = fdi_params(M, K, fault_mask=MASK, onset=40.0, delay=5.0, bias=-0.1)
    ks = np.arange(0, 30001, 50)
    flag, est = outputs(p, ks)
    _, est_ok = outputs(p_ok, ks)
    j, q = target
    np.testing.assert_array_equal(est[:, j, q], est_ok[:, 0, 2])
    np.testing.assert_array_equal(flag[:, j, q], (ks >= 4500).astype(float))
    assert np.all(est[:, 0, 2] == 0.0) and np.all(flag[:, 0, 2] == 0.0)


def test_scale_and_delay():
    p = fdi_params(M, K, fault_mask=MASK, onset=40.0, delay=2.5, scale=0.8)
    ks = np.arange(4250, 24251, 13)
    _, est = outputs(p, ks)
    t = ks * DT
    np.testing.assert_allclose(
        est[:, 0, 2], 0.8 * (0.05 * np.sin(0.02 * (t - 2.5)) + 0.6), atol=1e-12
    )


def test_noise_statistics_and_determinism():
    """noise_std = 0.02: the sample std of (u* - mean part) over 20,001 steps is 0.02 within 3 %
    (std error of a std estimate ~ 0.5 %), the mean within 4 sigma/sqrt(n); same key -> same numbers."""
    p = fdi_params(M, K, fault_mask=MASK, onset=40.0, delay=0.0, noise_std=0.02)
    ks = np.arange(4000, 24001)
    _, est = outputs(p, ks)
    resid = est[:, 0, 2] - (0.05 * np.sin(0.02 * ks * DT) + 0.6)
    assert abs(resid.std() / 0.02 - 1.0) < 0.03
    assert abs(resid.mean()) < 4 * 0.02 / np.sqrt(resid.size)
    _, est2 = outputs(p, ks)
    np.testing.assert_array_equal(est, est2)
    _, est3 = outputs(p, ks, key=jax.random.PRNGKey(1))
    assert not np.array_equal(est, est3)


def test_conformance_float64_and_batched_equals_single():
    ps = [
        fdi_params(M, K, fault_mask=MASK, onset=40.0, delay=d, bias=b, noise_std=0.01)
        for d, b in ((5.0, -0.1), (1.0, 0.2), (0.0, 0.0))
    ]
    P = jax.tree_util.tree_map(lambda *a: jnp.stack(a), *ps)
    k = jnp.asarray(9000)
    key = jax.random.PRNGKey(3)
    batched = jax.jit(jax.vmap(lambda p: fdi_output(MODEL, p, k, key)))(P)
    assert batched.estimate.dtype == jnp.float64 and batched.estimate.shape == (3, M, K)
    for i, p in enumerate(ps):
        single = fdi_output(MODEL, p, k, key)
        np.testing.assert_array_equal(np.asarray(batched.estimate[i]), np.asarray(single.estimate))
        np.testing.assert_array_equal(np.asarray(batched.flag[i]), np.asarray(single.flag))


def test_bad_configuration_is_rejected():
    with pytest.raises(ValueError, match="fdi.delay"):
        fdi_params(M, K, fault_mask=MASK, onset=40.0, delay=-1.0)
    with pytest.raises(ValueError, match="reported channel index 3"):
        isolation_routing(M, K, {(0, 2): (0, 3)})
    with pytest.raises(ValueError, match="fdi.routing must have shape"):
        fdi_params(M, K, fault_mask=MASK, onset=40.0, routing=identity_routing(M, 2))
    with pytest.raises(ValueError, match="noise_std"):
        fdi_params(M, K, fault_mask=MASK, onset=40.0, noise_std=-0.1)


def _loop(name="mehrabian-identification", **ov):
    return make_loop(
        ftc.load_scenario(name, {"simulation.horizon": 1.0, "simulation.record_every": 1, **ov})
    )


def test_held_time_signals_and_fault_and_fdi_profiles():
    """The fault (2) is 0.05 sin(0.02 t_k) + 0.6 on the snapped window, held over the step (the same
    value at the three stage times); the FDI reports u* = u_bar(t - 5) - 0.1 and the flag from 45 s."""
    loop = _loop(**{"simulation.horizon": 300.0})
    assert loop.actuator.holds_exogenous and loop.plant.holds_exogenous
    for k in (3999, 4000, 12345, 24000, 24001):
        t_k = k * 0.01
        table = loop._time_table(jnp.asarray(t_k), k=jnp.asarray(k))
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


def test_a_report_without_faults_to_report_is_refused():
    """Without an actuator stating faults the scripted report has nothing to report: validation
    refuses the loop naming the estimator and the actuator that would provide the faults."""
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
        "estimator": {"type": "scripted-fdi"},
    }
    with pytest.raises(ScenarioError) as err:
        ftc.load_scenario(raw)
    msg = str(err.value)
    assert "estimator scripted-fdi needs additive actuator faults" in msg
    assert 'actuator type = "euler-torque-allocation" with faults' in msg
    raw["actuator"]["faults"] = [
        {"spacecraft": 2, "channel": 1, "torque": "0.5", "start": 0.0, "end": 1.0}
    ]
    raw["estimator"]["isolation"] = [
        {"spacecraft": 1, "channel": 1, "reported_spacecraft": 2, "reported_channel": 1}
    ]
    with pytest.raises(ScenarioError, match=r"estimator.isolation\[0\]: spacecraft 1 channel 1"):
        ftc.load_scenario(raw)
