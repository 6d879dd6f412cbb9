"""The relative navigation filter (estimator ``relative-navigation-filter``).

Oracles: a textbook numpy Kalman filter on data drawn from the filter's own discrete model (the
component must give the same estimates to 1e-10), the empirical error covariance of that filter against
the Riccati steady state (sampling error of 20,000 correlated samples: 15 %), and, in a closed loop,
that the law really reads the estimate (its noise-driven delta-v drops) while the estimate stays within
the filter's stated accuracy of the truth.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from formation_ftc.api import check, load_scenario, simulate_with_metrics
from formation_ftc.components.estimators.relative_navigation_filter import (
    FilteredEstimator,
    RelativeNavigationFilter,
)
from formation_ftc.core.dynamics.cw import cw_matrices
from formation_ftc.design.kalman import discrete_model, steady_state_kalman
from formation_ftc.sim.components import Estimator, FlightInputs, Signal, component, static
from formation_ftc.sim.loop import NAVIGATION_ESTIMATE

N_LEO = math.sqrt(3.986004418e14 / 7000e3**3)
DT = 0.5
R = np.diag([0.1**2] * 3 + [1e-3**2] * 3)


def _model(q=1e-8):
    A, B = cw_matrices(N_LEO)
    return discrete_model(A, B, B, q, DT)


def _numpy_filter(model, y, f, mass):
    """Textbook filter: update with y_k, then predict with f_k / m (H = I)."""
    x, P = y[0].copy(), R.copy()
    out = []
    for k in range(len(y)):
        K = P @ np.linalg.inv(P + R)
        x = x + (y[k] - x) @ K.T
        P = (np.eye(6) - K) @ P @ (np.eye(6) - K).T + K @ R @ K.T
        out.append(x.copy())
        x = x @ model.phi.T + (f[k] / mass[:, None]) @ model.gamma.T
        P = model.phi @ P @ model.phi.T + model.qd
    return np.array(out), P


def _truth(model, steps, rng, mass):
    """Samples of the filter's own model: 2 spacecraft, random held forces, process and sensor noise."""
    x = np.array([[10.0, 0.0, 2.0, 0.0, 0.01, 0.0], [-5.0, 5.0, 0.0, 0.0, 0.0, 0.0]])
    L = np.linalg.cholesky(model.qd + 1e-30 * np.eye(6))
    Lr = np.linalg.cholesky(R)
    xs, ys, fs = [], [], []
    for _ in range(steps):
        f = rng.normal(scale=0.01, size=(2, 3))
        xs.append(x)
        ys.append(x + rng.normal(size=(2, 6)) @ Lr.T)
        fs.append(f)
        x = x @ model.phi.T + (f / mass[:, None]) @ model.gamma.T + rng.normal(size=(2, 6)) @ L.T
    return np.array(xs), np.array(ys), np.array(fs)


def test_component_equals_a_textbook_filter_and_its_errors_match_the_riccati_steady_state():
    model, mass = _model(), np.array([100.0, 120.0])
    xs, ys, fs = _truth(model, 400, np.random.default_rng(3), mass)
    comp = RelativeNavigationFilter(
        count=2,
        phi=model.phi,
        gamma=model.gamma,
        qd=model.qd,
        r=R,
        p0=R,
        nominal_mass=mass,
    )
    update = jax.jit(
        lambda s, y: comp.update(0.0, s, FlightInputs(y, None, None, None, None, None, None))
    )
    predict = jax.jit(lambda s, f: comp.predict(0.0, s, f, DT))
    state = comp.initial_state(ys[0])
    got = []
    for k in range(len(ys)):
        state, est = update(state, ys[k])
        got.append(np.asarray(est))
        state = predict(state, fs[k])
    ref, _ = _numpy_filter(model, ys, fs, mass)
    np.testing.assert_allclose(np.array(got), ref, rtol=1e-10, atol=1e-12)

    # the textbook filter (now known equal) on a long record: empirical error covariance vs Riccati
    xs, ys, fs = _truth(model, 20000, np.random.default_rng(4), mass)
    est, _ = _numpy_filter(model, ys, fs, mass)
    err = (est - xs)[2000:].reshape(-1, 6)
    P, K = steady_state_kalman(model.phi, model.qd, R)
    posterior = (np.eye(6) - K) @ P
    np.testing.assert_allclose(err.std(axis=0), np.sqrt(np.diag(posterior)), rtol=0.15)


@component
class _Spy(Estimator):
    """An estimator that returns the measurement it is given and keeps the last command."""

    count: int = static(default=2)

    def initial_state(self, measurement0):
        return jnp.zeros((2, 3))

    def update(self, t, state, inputs):
        return state, {"seen": inputs.measurement, "command": state}

    def predict(self, t, state, command, dt):
        return command

    def outputs(self, t, state, estimate):
        return {"seen": estimate["seen"]}

    def signals(self):
        return (Signal("seen", ("spacecraft", "component"), "m, m s-1", "what the spy read"),)

    def needs(self):
        return {"relative-state-measurement": "spy on it"}

    def provides(self):
        return frozenset({"spy"})


def test_an_estimator_on_the_filter_reads_the_textbook_estimate():
    # the chain's filter is the textbook filter (oracle: _numpy_filter), and the estimator behind it
    # reads that estimate, never the raw measurement; both time updates get the command
    model, mass = _model(), np.array([100.0, 120.0])
    _, ys, fs = _truth(model, 60, np.random.default_rng(5), mass)
    nav = RelativeNavigationFilter(
        count=2, phi=model.phi, gamma=model.gamma, qd=model.qd, r=R, p0=R, nominal_mass=mass
    )
    chain = FilteredEstimator(navigation_filter=nav, inner=_Spy())
    state = chain.initial_state(ys[0])
    got = []
    for k in range(len(ys)):
        state, est = chain.update(
            0.0, state, FlightInputs(ys[k], None, None, None, None, None, None)
        )
        np.testing.assert_array_equal(est["seen"], est[NAVIGATION_ESTIMATE])
        got.append(np.asarray(est[NAVIGATION_ESTIMATE]))
        state = chain.predict(0.0, state, jnp.asarray(fs[k]), DT)
        np.testing.assert_array_equal(state["inner"], fs[k])
    ref, _ = _numpy_filter(model, ys, fs, mass)
    np.testing.assert_allclose(np.array(got), ref, rtol=1e-10, atol=1e-12)
    out = chain.outputs(0.0, state, est)
    assert {"navigation_estimate", "navigation_covariance", "navigation_nis", "seen"} <= set(out)
    assert chain.provides() == {"spy", "navigation-records"}
    assert set(chain.needs()) == {"relative-state-measurement", "translational-state"}
    assert [s.name for s in chain.signals()][-1] == "seen"


SCENARIO = """
[scenario]
name = "nav-loop"
method = "composed"

[simulation]
horizon = 600.0
dt = 0.5
record_every = 1

[plant]
type = "clohessy-wiltshire"
semi_major_axis = 7000e3
mass = [100.0, 120.0]
initial_position = [[10.0, 0.0, 2.0], [-5.0, 5.0, 0.0]]

[sensors]
type = "relative-state"
position_noise_std = 0.1
velocity_noise_std = 0.001

[controller]
type = "lqr"
semi_major_axis = 7000e3
nominal_mass = [100.0, 120.0]
max_position_error = 1.0
max_velocity_error = 0.01
max_acceleration = 2e-3
desired_position = ["0", "0", "0"]
{estimator}
[[metrics]]
name = "dv"
signal = "delta_v"
reduce = "last"
spacecraft = "sum"
units = "m s-1"
"""

FILTER = """
[estimator]
type = "relative-navigation-filter"
semi_major_axis = 7000e3
position_noise_std = 0.1
velocity_noise_std = 0.001
acceleration_noise_psd = 1e-10
nominal_mass = [100.0, 120.0]
"""


def _run(tmp_path, estimator):
    path = tmp_path / "s.toml"
    path.write_text(SCENARIO.replace("{estimator}", estimator))
    return path, *simulate_with_metrics(load_scenario(path))


def test_the_law_flies_on_the_filtered_state(tmp_path):
    _, ds_raw, _ = _run(tmp_path, "")
    path, ds, _ = _run(tmp_path, FILTER)

    def late_dv(d):  # delta-v after the acquisition (t > 300 s): what the noise costs [m/s]
        dv = d["delta_v"].sel(time=[300.0, 600.0]).values.sum(axis=-1)
        return dv[1] - dv[0]

    # LQR on 0.1 m / 1 mm/s noise: the filter removes most of the noise-driven thrust
    assert late_dv(ds) < late_dv(ds_raw) / 3
    err = ds["navigation_estimate"].values[:, :, :3] - ds["position"].values
    late = ds.time.values > 300.0
    sigma = ds["navigation_sigma"].values[-1, :3]
    # the error is correlated over the filter's long averaging time (tens of seconds): 300 s of two
    # spacecraft are a handful of independent samples, so the check is the order of magnitude
    rms = np.sqrt(np.mean(err[late] ** 2, axis=(0, 1)))
    assert np.all(rms < 3 * sigma) and np.all(rms > sigma / 3), (rms, sigma)
    conds = {c.name: c for c in check(load_scenario(path))}
    assert conds["navigation filter: steady-state error dynamics stable"].holds is True


def test_stated_nominal_masses_must_fit_the_formation(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(SCENARIO.replace("{estimator}", FILTER.replace("[100.0, 120.0]", "[100.0]")))
    with pytest.raises(ValueError, match="estimator.nominal_mass: 1 values for 2 spacecraft"):
        load_scenario(path)
