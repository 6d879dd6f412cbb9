"""Fault detection and isolation from navigation residuals (estimator ``residual-fdi``, evaluation
``fdi-scores``).

Oracles: the parity residual of a thruster bias on a free-drifting formation, hand-computed from the
exact CW discretisation (gamma b / m); the CUSUM's detection step in closed form for a constant
standardised shift (k* = floor(h / (mu - nu)) + 1); and, with navigation noise, no alarm without a fault
and a correctly isolated alarm with one.
"""

from __future__ import annotations

import math

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
    _, quiet = _run(
        tmp_path, sensors=NOISY, kind="none", residual=residual, test="cusum", threshold=20.0
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
