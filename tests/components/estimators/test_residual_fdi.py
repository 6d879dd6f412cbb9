"""Fault detection and isolation from navigation residuals (estimator ``residual-fdi``, evaluation
``fdi-scores``).

Oracles: the parity residual of a thruster bias on a free-drifting formation, hand-computed from the
exact CW discretisation (gamma b / m); the CUSUM's detection step in closed form for a constant
standardised shift (k* = floor(h / (mu - nu)) + 1); and, with navigation noise, no alarm without a fault
and a correctly isolated alarm with one.
"""

from __future__ import annotations

import math

import jax
import numpy as np
import pytest

from formation_ftc.api import load_scenario, simulate_with_metrics
from formation_ftc.core.dynamics.cw import cw_matrices
from formation_ftc.design.kalman import discrete_model

N_LEO = math.sqrt(3.986004418e14 / 7000e3**3)
DT, ONSET, BIAS, MASS = 0.5, 20.0, 0.05, 120.0  # s, s, N, kg (spacecraft 2)

SCENARIO = """
[scenario]
name = "fdi"
method = "composed"

[simulation]
horizon = {horizon}
dt = 0.5
record_every = 1

[plant]
type = "clohessy-wiltshire"
semi_major_axis = 7000e3
mass = [100.0, 120.0]
initial_position = [[10.0, 0.0, 2.0], [-5.0, 5.0, 0.0]]
{sensors}
[controller]
type = "none"

[actuator]
type = "fault-battery"
kind = "{kind}"
spacecraft = 2
axis = 1
onset = 20.0
bias = {bias}

[estimator]
type = "residual-fdi"
semi_major_axis = 7000e3
position_noise_std = 0.1
velocity_noise_std = 0.001
nominal_mass = [100.0, 120.0]
residual = "{residual}"
test = "{test}"
drift = {drift}
threshold = {threshold}

[[evaluations]]
type = "fdi-scores"

[[metrics]]
name = "detection_delay"
signal = "fdi_pending"
reduce = "integral"
units = "s"

[[metrics]]
name = "missed"
signal = "fdi_missed"
reduce = "last"

[[metrics]]
name = "false_alarm"
signal = "fdi_false_alarm"
reduce = "max"

[[metrics]]
name = "isolated"
signal = "fdi_correct_isolation"
reduce = "last"
"""

NOISY = """
[sensors]
type = "relative-state"
position_noise_std = 0.1
velocity_noise_std = 0.001
"""


#: the scenario's fields: a noise-free parity residual with a threshold never reached
FIELDS = dict(
    horizon=60.0,
    sensors="",
    kind="bias",
    residual="parity",
    test="fixed",
    drift=0.5,
    threshold=1e6,
    bias=BIAS,
)


def _run(tmp_path, **kw):
    path = tmp_path / "fdi.toml"
    path.write_text(SCENARIO.format(**{**FIELDS, **kw}))
    return simulate_with_metrics(load_scenario(path))


def _hand_parity_z() -> np.ndarray:
    """Standardised velocity parity residual of spacecraft 2 for the along-track bias (3,)."""
    A, B = cw_matrices(N_LEO)
    m = discrete_model(A, B, B, 1e-10, DT)  # the section's default acceleration noise density
    R = np.diag([0.1**2] * 3 + [1e-3**2] * 3)
    S = R + m.phi @ R @ m.phi.T + m.qd
    e = m.gamma @ np.array([0.0, BIAS / MASS, 0.0])
    return e[3:] / np.sqrt(np.diag(S)[3:])


def test_parity_residual_of_a_bias_equals_the_hand_computed_response(tmp_path):
    ds, _ = _run(tmp_path)
    stat = ds["fdi_statistic"].values  # |z| per (time, spacecraft, axis)
    t = ds.time.values
    z = _hand_parity_z()
    after = t >= ONSET + DT  # the first residual that sees the bias: one step after the onset
    got = stat[after][:, 1, :]
    np.testing.assert_allclose(got, np.broadcast_to(np.abs(z), got.shape), rtol=1e-6, atol=1e-9)
    assert np.max(stat[~after]) < 1e-6 and np.max(stat[:, 0, :]) < 1e-6  # no fault, no residual
    assert abs(z[1]) > 10 * max(abs(z[0]), abs(z[2]))  # the faulty axis dominates


def test_cusum_detects_at_the_closed_form_step_and_isolates(tmp_path):
    mu = abs(_hand_parity_z()[1])
    drift, h = 0.25 * mu, 5.0 * mu
    k_star = math.floor(h / (mu - drift)) + 1  # steps of residual before the statistic exceeds h
    ds, m = _run(tmp_path, test="cusum", drift=drift, threshold=h)
    assert m["detection_delay"] == pytest.approx(k_star * DT, abs=1e-9)
    detected_at = ds.time.values[np.argmax(ds["fdi_detected"].values > 0.5)]
    assert detected_at == pytest.approx(ONSET + k_star * DT)
    assert m["missed"] == 0.0 and m["false_alarm"] == 0.0 and m["isolated"] == 1.0


@pytest.mark.parametrize("residual", ["kalman", "parity"])
def test_noisy_navigation_no_false_alarm_then_a_correct_detection(tmp_path, residual):
    # both runs 300 s: one program (the fault kind and its bias are values, not the structure)
    _, quiet = _run(
        tmp_path,
        horizon=300.0,
        sensors=NOISY,
        kind="none",
        residual=residual,
        test="cusum",
        threshold=20.0,
    )
    assert quiet["false_alarm"] == 0.0 and quiet["missed"] == 0.0
    # 0.5 N: the one-step parity residual sees dt b / m against sqrt(2) x 1 mm/s of noise, 1.5 sigma
    # per step (0.05 N would be 0.15 sigma, below the CUSUM's drift: the Kalman innovation detects it)
    _, faulty = _run(
        tmp_path,
        horizon=300.0,
        bias=0.5,
        sensors=NOISY,
        residual=residual,
        test="cusum",
        threshold=20.0,
    )
    assert faulty["missed"] == 0.0 and faulty["false_alarm"] == 0.0 and faulty["isolated"] == 1.0
    assert 0.0 < faulty["detection_delay"] < 200.0


def test_fdi_scores_need_the_fault_battery(tmp_path):
    path = tmp_path / "bad.toml"
    text = SCENARIO.format(**{**FIELDS, "threshold": 5.0})
    text = text.replace('type = "residual-fdi"', 'type = "relative-navigation-filter"').replace(
        'residual = "parity"\ntest = "fixed"\ndrift = 0.5\nthreshold = 5.0\n', ""
    )
    path.write_text(text)
    with pytest.raises(ValueError) as err:
        load_scenario(path)
    msg = str(err.value)  # the evaluation and the estimator that would provide what it needs
    assert "fdi-scores needs a fault detector's latched alarm" in msg, msg
    assert 'estimator type = "residual-fdi"' in msg, msg


SATURATING = """
[controller]                # holds the spacecraft at the origin from 10 m: commands far above 0.2 N
type = "pd"
mode = "sampled"
kp = 2.0
kd = 30.0
desired_position = ["0", "0", "0"]
nominal_mass = [100.0, 120.0]
"""


@pytest.mark.parametrize("limit", [None, 0.2])
def test_a_thrust_limit_is_not_a_fault_when_the_rating_is_stated(tmp_path, limit):
    """No fault, a 0.2 N per-axis limit on the truth, a law that saturates: the parity residual of a
    saturated step is the force the limit cut (up to |u| dt / m), an alarm; with the rated thrust
    stated (``force_limit``) those channels are not tested and no alarm is raised, while the residual
    statistic of the channels below the rating stays tested."""
    text = SCENARIO.format(**{**FIELDS, "kind": "none", "test": "fixed", "threshold": 5.0})
    text = text.replace('[controller]\ntype = "none"\n', SATURATING)
    text = text.replace('kind = "none"', 'kind = "none"\nsaturation = 0.2')
    if limit is not None:
        text = text.replace("threshold = 5.0", f"threshold = 5.0\nforce_limit = {limit}")
    path = tmp_path / "sat.toml"
    path.write_text(text)
    ds, m = simulate_with_metrics(load_scenario(path))
    saturated = np.abs(ds["command"].values) >= 0.2
    assert saturated[:10].all(axis=0).sum() == 4  # the acquisition saturates the 4 displaced axes
    if limit is None:
        assert m["false_alarm"] == 1.0
    else:
        assert m["false_alarm"] == 0.0 and float(ds["fdi_statistic"].values.max()) < 5.0


@pytest.mark.parametrize("at_limit", ["skip", "clip"])
def test_a_fault_of_a_saturated_thruster_shows_when_the_model_clips(tmp_path, at_limit):
    """Spacecraft 2's along-track thruster is held at the 0.2 N rating for the whole run (acquisition
    from 5 m) and goes out at 20 s; noise-free Kalman innovation, CUSUM. With the clipped command as
    the model's force (clip) the healthy run gives no alarm and the outage is detected and isolated
    to that channel within 5 s. Skipping the saturated channel is not enough for a Kalman residual:
    its prediction carries the unclipped command, the error leaks into the tested radial channel
    through the Coriolis coupling, and the healthy run raises a false alarm (why clip exists; the
    parity residual, memoryless, is the one to pair with skip)."""
    text = SCENARIO.format(**{**FIELDS, "residual": "kalman", "test": "cusum", "threshold": 5.0})
    text = text.replace('[controller]\ntype = "none"\n', SATURATING)
    text = text.replace(
        "threshold = 5.0", f'threshold = 5.0\nforce_limit = 0.2\nat_limit = "{at_limit}"'
    )
    kinds = ("none", "outage") if at_limit == "clip" else ("none",)
    for kind in kinds:
        path = tmp_path / f"sat-{kind}.toml"
        path.write_text(text.replace('kind = "bias"', f'kind = "{kind}"\nsaturation = 0.2'))
        ds, m = simulate_with_metrics(load_scenario(path))
        along = ds["command"].values[:, 1, 1]  # spacecraft 2, along-track [N]
        assert np.all(np.abs(along) >= 0.2)  # saturated throughout
        if at_limit == "skip":
            assert m["false_alarm"] == 1.0
        elif kind == "none":
            assert m["false_alarm"] == 0.0
        else:
            assert m["missed"] == 0.0 and m["isolated"] == 1.0 and m["detection_delay"] < 5.0


def test_clipping_needs_the_rating(tmp_path):
    text = SCENARIO.format(**FIELDS).replace(
        "threshold = 1000000.0", 'threshold = 1e6\nat_limit = "clip"'
    )
    path = tmp_path / "noclip.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match="at_limit.*force_limit"):
        load_scenario(path)


# ----------------------------------------------------------------------------------- identification
def _batch_least_squares(phi, e, noise_var, prior_cov, forgetting):
    """The exponentially weighted least-squares solution with a Gaussian prior (the closed form the RLS
    recursion computes step by step): minimise sum_k lambda^(K-1-k) (e_k - phi_k' theta)^2 / noise_var
    + lambda^K theta' P0^-1 theta."""
    K = len(e)
    w = forgetting ** np.arange(K - 1, -1, -1) / noise_var
    info = forgetting**K * np.linalg.inv(prior_cov) + (phi * w[:, None]).T @ phi
    theta = np.linalg.solve(info, (phi * w[:, None]).T @ e)
    return theta, np.linalg.inv(info)


@pytest.mark.parametrize("forgetting", [1.0, 0.98])
def test_rls_identification_equals_the_weighted_least_squares_solution(forgetting):
    """identify_channels, step by step, equals the closed-form weighted least squares with the prior
    (every channel at once; rtol 1e-8: the recursion and the normal equations round differently)."""
    from formation_ftc.components.estimators.residual_fdi import identify_channels

    rng = np.random.default_rng(3)
    n, steps = 2, 120
    gain, noise_var = np.array([0.5, 0.4, 0.5]), np.array([2e-6, 1e-6, 3e-6])
    true = rng.uniform([-0.6, -1e-4], [0.2, 1e-4], size=(n, 3, 2))  # [effectiveness - 1, bias]
    accel = rng.normal(0.0, 2e-3, size=(steps, n, 3))
    e = gain * ((true[..., 0]) * accel + true[..., 1]) + rng.normal(
        0, np.sqrt(noise_var), (steps, n, 3)
    )
    prior = np.diag([1.0, 1e-6])
    theta, cov = np.zeros((n, 3, 2)), np.broadcast_to(prior, (n, 3, 2, 2))
    for k in range(steps):
        phi = gain[None, :, None] * np.stack([accel[k], np.ones((n, 3))], axis=-1)
        theta, cov = identify_channels(theta, cov, e[k], phi, noise_var, forgetting)
    for i in range(n):
        for j in range(3):
            phi = gain[j] * np.stack([accel[:, i, j], np.ones(steps)], axis=1)
            ref, ref_cov = _batch_least_squares(phi, e[:, i, j], noise_var[j], prior, forgetting)
            np.testing.assert_allclose(np.asarray(theta)[i, j], ref, rtol=1e-8, atol=1e-14)
            np.testing.assert_allclose(np.asarray(cov)[i, j], ref_cov, rtol=1e-6, atol=1e-18)


def test_a_constant_command_leaves_the_effectiveness_unidentified():
    """A command that never varies makes the effectiveness and the bias indistinguishable (collinear
    regressors): the effectiveness's standard deviation stays near its prior, however long the run;
    the same number of samples of a varying command pins it down."""
    from formation_ftc.components.estimators.residual_fdi import identify_channels

    # one program for the 4,000 steps, not 4,000 dispatches of each of its operations
    identify = jax.jit(identify_channels)
    gain, noise_var = np.array([0.5, 0.5, 0.5]), np.full(3, 1e-6)
    prior = np.broadcast_to(np.diag([1.0, 1e-4]), (1, 3, 2, 2))
    stds = {}
    for name, accel in {"constant": lambda k: 2e-3, "varying": lambda k: 2e-3 * (-1) ** k}.items():
        theta, cov = np.zeros((1, 3, 2)), prior
        for k in range(2000):
            a = np.full((1, 3), accel(k))
            phi = gain[None, :, None] * np.stack([a, np.ones_like(a)], axis=-1)
            theta, cov = identify(theta, cov, 0.5 * -0.5 * a, phi, noise_var, 1.0)
        stds[name] = float(np.sqrt(np.asarray(cov)[0, 0, 0, 0]))
    assert stds["constant"] > 0.05  # not identified at the default identification_std
    assert stds["varying"] < 0.03  # 1e-3 / (0.5 * 2e-3 * sqrt(2000)) = 0.022


@pytest.mark.parametrize("onset", [0.0, 60.0])
def test_closed_loop_identifies_a_loss_of_effectiveness_and_leaves_healthy_channels_at_one(onset):
    """cw-fdi-identification: a 50 % loss of effectiveness while the LQR acquires from a few hundred
    metres (its transient excites every channel). The faulty channel is identified at 0.5 within 0.02,
    the healthy ones within 0.03 of 1, the fault detected and isolated. With the onset at 60 s the
    channel restarts from the prior at the alarm: without the restart, and no forgetting, its estimate
    would average 60 s of a healthy thruster with the faulty one."""
    ds, m = simulate_with_metrics(load_scenario("cw-fdi-identification", {"actuator.onset": onset}))
    eff = ds["fdi_effectiveness"].values[-1]
    assert abs(eff[1, 1] - 0.5) < 0.02
    np.testing.assert_allclose(np.delete(eff.ravel(), 4), 1.0, atol=0.03)
    assert m["correct_isolation"] == 1.0 and m["false_identification"] == 0.0
    assert m["time_to_identify"] < 20.0


def test_without_excitation_nothing_is_identified():
    """cw-fdi-thruster-bias's small offsets leave the LQR's commands noise-driven (about 0.03 N): after
    400 s no channel is identified -- its effectiveness is NaN, not a number -- and no standard
    deviation exceeds the prior's 1 (the covariance does not wind up)."""
    overrides = {
        "actuator.kind": "loss_of_effectiveness",
        "actuator.effectiveness": 0.5,
        "actuator.bias": 0.0,
        "estimator.identification": "rls",
        "estimator.forgetting": 0.99,
        "simulation.horizon": 400.0,
    }
    ds, _ = simulate_with_metrics(load_scenario("cw-fdi-thruster-bias", overrides))
    assert np.isnan(ds["fdi_effectiveness"].values[-1]).all()
    std = ds["fdi_effectiveness_std"].values
    assert (std[-1] > 0.05).all() and (std <= 1.0 + 1e-12).all()


def test_the_law_flies_on_the_fdis_filter_while_the_fdi_watches():
    """cw-fdi-thruster-bias with fly_on_filter: the LQR reads the FDI's Kalman estimate instead of the
    raw measurement (recorded as navigation_estimate; the command, computed from it, falls several-fold,
    as with relative-navigation-filter), and the same FDI still detects and isolates the 0.05 N bias
    without a false alarm. Before the fault the estimate is within 1 cm of the truth (the measurement's
    noise is 0.1 m). After it, a filter that models a healthy thruster is off by about a metre along
    track on the faulty spacecraft; with identification it predicts that channel with the identified
    bias and stays within 5 cm. The parity residual keeps no state estimate: fly_on_filter needs the
    Kalman residual."""
    from formation_ftc.config.loader import ScenarioError

    raw, _ = simulate_with_metrics(load_scenario("cw-fdi-thruster-bias"))
    errors = {}
    for identification in ("off", "rls"):
        overrides = {"estimator.fly_on_filter": True, "estimator.identification": identification}
        ds, m = simulate_with_metrics(load_scenario("cw-fdi-thruster-bias", overrides))
        assert "navigation_estimate" in ds and "navigation_estimate" not in raw
        assert np.abs(ds["command"].values).sum() < 0.5 * np.abs(raw["command"].values).sum()
        assert m["false_alarm"] == 0.0 and m["correct_isolation"] == 1.0
        t = ds.time.values
        error = np.abs(ds["navigation_estimate"].values[..., :3] - ds["position"].values)
        assert error[(t > 50) & (t < 400)].mean() < 0.01
        errors[identification] = error[t > 600].mean(axis=0)  # (spacecraft, axis) [m]
    assert errors["off"][1, 1] > 0.5  # the unmodelled fault biases the filter
    assert errors["rls"].max() < 0.05
    with pytest.raises(ScenarioError, match="fly_on_filter"):
        load_scenario(
            "cw-fdi-thruster-bias",
            {"estimator.fly_on_filter": True, "estimator.residual": "parity"},
        )


@pytest.mark.parametrize("window_s", [0.5, 5.0])
def test_window_identification_of_an_exact_trajectory(window_s):
    """The FDI fed, step by step, an exact (noise-free) CW trajectory of two spacecraft whose thruster
    (spacecraft 2, along track) delivers 50 % of a varying command: after a few windows of 1 or 10
    steps the identified effectiveness is 0.5 and the healthy channels' 1 (to 1e-3: the prior's weight
    is all that separates the estimate from the exact value). The oracle is the trajectory itself,
    propagated with the exact discretisation (phi, gamma) the FDI's model uses."""
    from formation_ftc.api import build_loop
    from formation_ftc.sim.components import FlightInputs, StepContext

    overrides = {
        "estimator.identification": "rls",
        "estimator.forgetting": 1.0,
        "estimator.identification_window": window_s,
        "estimator.velocity_noise_std": 1e-6,
        "estimator.position_noise_std": 1e-4,
    }
    fdi = build_loop(load_scenario("cw-fdi-identification", overrides)).estimator
    rng = np.random.default_rng(1)
    x = np.zeros((2, 6))
    x[:, :3] = [[300.0, -200.0, 50.0], [-150.0, 250.0, -80.0]]
    state = fdi.initial_state(x.copy())
    mass = np.asarray(fdi.nominal_mass)[:, None]

    @jax.jit  # one program for the 200 steps, not 200 x its operations
    def step(k, state, x, force):
        t = k * DT
        sc = StepContext(k=k, t=t, dt=DT)
        state, est = fdi.update(t, state, FlightInputs(x, None, None, None, None, None, sc))
        return fdi.predict(t, state, force, DT), est

    for k in range(200):
        force = rng.normal(0.0, 0.5, (2, 3))
        applied = force.copy()
        applied[1, 1] *= 0.5
        state, est = step(np.asarray(k), state, x, force)
        x = x @ np.asarray(fdi.phi).T + (applied / mass) @ np.asarray(fdi.gamma).T
    eff = np.asarray(est["effectiveness"])
    assert bool(np.asarray(est["identified"]).all())
    np.testing.assert_allclose(eff[1, 1], 0.5, atol=1e-3)
    np.testing.assert_allclose(np.delete(eff.ravel(), 4), 1.0, atol=1e-3)
