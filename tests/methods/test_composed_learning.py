"""Gui2022's iterative learning observer + LOF2TC (CW design, acceleration commands) on Li2020's nonlinear
elliptic relative dynamics (force-driven point masses): scenario compose-gui2022-on-li2020."""

from __future__ import annotations

import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.cli import main
from formation_ftc.config.loader import ScenarioError
from formation_ftc.methods.composed import make_loop

NAME = "compose-gui2022-on-li2020"
MU = 3.986004418e14
A_REF, E_REF = 7000e3, 0.02
MASS = np.array([100.0, 120.0, 115.0, 108.0])
#: 12 s at dt = 0.001 s; the x step fault from 4 s, the z fault from 8 s
SHORT = {"simulation.horizon": 12.0, "actuator.onset": [4.0, 0.0, 8.0]}


def _lumped_input(ds) -> np.ndarray:
    """What the ILO's CW model misses, per unit mass, from the recorded true state (independent numpy
    truth): nonlinear elliptic relative acceleration minus the CW model's A q (on-board n = sqrt(mu/a^3)),
    plus Li2020's disturbance h_i(t) / m_i, plus the true fault F_i / m_i [m/s^2]."""
    t = ds.time.values[:, None]
    x, y, z = np.moveaxis(ds.position.values, -1, 0)
    vx, vy, _ = np.moveaxis(ds.velocity.values, -1, 0)
    th = ds.true_anomaly.values[:, None]
    p = A_REF * (1 - E_REF**2)
    k = 1 + E_REF * np.cos(th)
    rc, thd = p / k, np.sqrt(MU / p**3) * k**2
    thdd = -2 * E_REF * np.sin(th) * thd**2 / k
    r3 = ((rc + x) ** 2 + y**2 + z**2) ** 1.5
    acc = np.stack(
        [
            2 * thd * vy + thd**2 * x + thdd * y - MU * (rc + x) / r3 + MU / rc**2,
            -2 * thd * vx + thd**2 * y - thdd * x - MU * y / r3,
            -MU * z / r3,
        ],
        axis=-1,
    )
    n = np.sqrt(MU / A_REF**3)
    cw = np.stack([3 * n**2 * x + 2 * n * vy, -2 * n * vx, -(n**2) * z], axis=-1)
    i = np.arange(1, 5)[None, :]
    h = 0.05 * np.stack(
        [
            (i + 1) * np.cos(0.1 * t) + 2 * i * np.sin(0.2 * t),
            2 * i * np.cos(0.2 * t) + 3 * i + 0 * t,
            (i - 3) * np.sin(0.1 * t) - 2 * i,
        ],
        axis=-1,
    )
    fault = np.zeros_like(acc)
    fault[..., 0] = np.where(t >= 4.0, 0.5, 0.0)
    fault[..., 2] = np.where(
        t >= 8.0, 0.25 * np.sin(0.05 * t + np.pi / 4) - 0.2 * np.exp(-0.1 * t), 0.0
    )
    return acc - cw + h / MASS[None, :, None] + fault, fault


def test_scenario_runs_records_metrics_check_and_the_ilo_reconstructs_fault_plus_mismatch():
    scn = ftc.load_scenario(NAME, SHORT)
    ds, m = ftc.simulate_with_metrics(scn)
    for var in (
        "position",
        "velocity",
        "position_error",
        "command",
        "acceleration_command",
        "applied",
        "fault",
        "fault_acceleration",
        "fault_estimate",
        "fault_error",
        "estimation_error",
        "learning_gain",
        "tracking_error",
        "position_tracking_error",
        "delta_v",
    ):
        assert var in ds, var
    assert ds.sizes["spacecraft"] == 4 and ds.sizes["time"] == 121
    # metrics: finite, except those whose window starts after this shortened run
    late = {
        "fault_rms_error_before_onset",
        "fault_rms_error_after_onset",
        "max_position_error_before_fault",
        "max_position_error_after_fault",
    }
    assert set(m) >= late | {"final_position_error", "max_learning_gain", "delta_v_sc1"}
    assert all(np.isnan(m[k]) for k in late)
    assert all(np.isfinite(v) for k, v in m.items() if k not in late)
    assert all(c.holds for c in ftc.check(scn))

    # acceleration -> force on board: f_i = m_i^nom u_i with m_nom = the plant's masses
    np.testing.assert_allclose(
        ds.command.values, MASS[None, :, None] * ds.acceleration_command.values, rtol=1e-12, atol=0
    )
    # the fault is applied on the truth side, in newtons (Gui2022's accelerations times each true mass)
    lumped, fault = _lumped_input(ds)
    np.testing.assert_allclose(
        ds.applied.values - ds.command.values, ds.fault.values, rtol=0, atol=1e-9
    )
    np.testing.assert_allclose(ds.fault_acceleration.values, fault, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ds.fault.values, MASS[None, :, None] * fault, rtol=0, atol=1e-9)

    # the ILO's F_hat reconstructs the fault plus the model mismatch it cannot tell apart (same channel):
    # away from the onset samples within 1e-2 m/s^2 (2 % of the 0.5 m/s^2 step), although the mismatch
    # alone (up to ~9e-3 m/s^2) is not small against the observer's gamma = 3.2e-3 m/s^2
    t = ds.time.values
    settled = (t >= 1.0) & (np.abs(t - 4.0) >= 0.5) & (np.abs(t - 8.0) >= 0.5)
    err = np.abs(ds.fault_estimate.values - lumped)[settled]
    assert err.max() < 1e-2, err.max()
    mismatch = np.abs(lumped - fault)[settled].max()
    assert mismatch > 2e-3  # the mismatch is really there (an ILO on the CW plant would see none)
    assert (
        np.abs(ds.fault_estimate.values[t >= 5.0, :, 0] - 0.5).max() < 0.02
    )  # the x step is found

    # LOF2TC pulls every spacecraft towards its nominal CW ellipse from the Li2020 initial positions
    e = np.linalg.norm(ds.position_error.values, axis=-1)
    assert np.all(e[-1] < 0.7 * e[0])


def test_onboard_model_uses_the_reference_mean_motion_and_design_gains():
    """Default on-board n = sqrt(mu / a^3) of [reference]; gains = 'lmi' / 'care' are designed at that n:
    poles of A - L1 in the disk S(-5, 2), A - B K Hurwitz, K solves the CARE (numpy, independent)."""
    from scipy.linalg import solve_continuous_are

    from formation_ftc.core.dynamics.cw import cw_matrices

    scn = ftc.load_scenario(
        NAME, {"estimator.gains": "lmi", "controller.gains": "care", "simulation.horizon": 1.0}
    )
    loop = make_loop(scn)
    ilo = loop.estimator.inner
    law = loop.controller.law
    n = np.sqrt(MU / A_REF**3)
    assert float(ilo.mean_motion) == pytest.approx(n, rel=1e-15)
    assert float(law.mean_motion) == pytest.approx(n, rel=1e-15)
    np.testing.assert_array_equal(np.asarray(loop.controller.nominal_mass), MASS)
    np.testing.assert_array_equal(np.asarray(loop.estimator.nominal_mass), MASS)
    A, B = cw_matrices(n)
    poles = np.linalg.eigvals(A - np.asarray(ilo.L1))
    assert np.all(np.abs(poles + 5.0) < 2.0), poles
    K = np.asarray(law.K)
    assert np.linalg.eigvals(A - B @ K).real.max() < 0
    P_ref = solve_continuous_are(
        A, B, 4e-5 * np.eye(6), np.eye(3)
    )  # CARE (34), Q = 4e-5 I6, R = I3
    np.testing.assert_allclose(K, B.T @ P_ref, rtol=1e-8, atol=1e-12)


def test_mass_error_on_board_is_an_actuator_gain_error_the_ilo_sees():
    """With m_nom = 0.9 m the plant receives 0.9 of the commanded acceleration; the conversion uses
    m_nom on both sides (force = m_nom u, ILO model input = f / m_nom)."""
    scn = ftc.load_scenario(
        NAME, {"controller.nominal_mass": list(0.9 * MASS), "simulation.horizon": 1.0}
    )
    loop = make_loop(scn)
    np.testing.assert_allclose(np.asarray(loop.controller.nominal_mass), 0.9 * MASS)
    np.testing.assert_allclose(np.asarray(loop.estimator.nominal_mass), 0.9 * MASS)


def _raw(**slots):
    base = {
        "scenario": {"name": "bad", "method": "composed"},
        "simulation": {"horizon": 1.0, "dt": 0.001},
        "plant": {
            "type": "quaternion-rigid-body",
            "inertia": [20.0, 18.0, 15.0],
            "initial_quaternion": [[0.0, 0.0, 0.0, 1.0]] * 4,
        },
        "controller": {
            "type": "gui2022-cof2tc",
            "K": [
                [0.0063, 0, 0, 0.1127, 0, 0],
                [0, 0.0063, 0, 0, 0.1126, 0],
                [0, 0, 0.0063, 0, 0, 0.1126],
            ],
            "desired_state": [[0.0] * 6] * 4,
            "mean_motion": 0.001,
        },
    }
    base.update(slots)
    return base


ILO = {
    "type": "iterative-learning-observer",
    "gains": "lmi",
    "Q1": [0.99, 0.99, 0.99],
    "Q2": 0.999,
    "gamma": 3.231e-3,
    "learning_interval": 0.001,
    "mean_motion": 0.001,
}
#: the ILO with given gains (no LMI design) and an attitude law a quaternion plant can fly
ILO_PRINTED = {**ILO, "gains": "printed", "L1": np.eye(6).tolist(), "L2": np.zeros((3, 6)).tolist()}
ATTITUDE_LAW = {"type": "attitude-pd", "K_p": 1.0, "K_d": 1.0}


@pytest.mark.parametrize(
    "slots, needles",
    [
        (
            {},
            ("controller gui2022-cof2tc", "plant quaternion-rigid-body", "torque"),
        ),  # a CW law on rigid-body attitudes
        (  # the ILO on rigid-body attitudes (under an attitude law): no relative state to observe
            {"estimator": ILO_PRINTED, "controller": ATTITUDE_LAW},
            (
                "estimator iterative-learning-observer needs the measured (N, 6) relative position",
                'sensors type = "relative-state"',
            ),
        ),
        (
            {
                "plant": {
                    "type": "relative-lvlh",
                    "mass": [100.0] * 3,
                    "initial_position": [[1.0, 0, 0]] * 3,
                },
                "reference": {"type": "keplerian", "semi_major_axis": 7000e3},
            },
            ("controller.desired_state", "4 rows for 3 spacecraft"),
        ),
        (
            {
                "plant": {
                    "type": "relative-lvlh",
                    "mass": [100.0] * 4,
                    "initial_position": [[1.0, 0, 0]] * 4,
                },
                "reference": {"type": "keplerian", "semi_major_axis": 7000e3},
                "estimator": {**ILO, "learning_interval": 0.0015},
            },
            ("estimator.learning_interval", "integer multiple"),
        ),
        ({"estimator": {**ILO, "gains": "printed"}}, ("L1 and L2", "required")),
    ],
)
def test_impossible_compositions_are_rejected_at_validation(slots, needles):
    with pytest.raises(ScenarioError) as err:
        ftc.load_scenario(_raw(**slots))
    for needle in needles:
        assert needle in str(err.value), (needle, str(err.value))


def test_cli_rejects_the_ilo_on_an_attitude_plant_with_exit_2(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text("""
[scenario]
name = "bad"
method = "composed"
[simulation]
horizon = 1.0
dt = 0.001
[plant]
type = "quaternion-rigid-body"
inertia = [20.0, 18.0, 15.0]
initial_quaternion = [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 1.0]]
[estimator]
type = "iterative-learning-observer"
L1 = [[1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 0, 1, 0, 0, 0],
      [0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 1, 0], [0, 0, 0, 0, 0, 1]]
L2 = [[0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 1, 0], [0, 0, 0, 0, 0, 1]]
Q1 = [0.99, 0.99, 0.99]
Q2 = 0.999
gamma = 3.231e-3
learning_interval = 0.001
mean_motion = 0.001
[controller]
type = "attitude-pd"
K_p = 1.0
K_d = 1.0
""")
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "estimator iterative-learning-observer needs the measured (N, 6)" in err
    assert '"relative-state"' in err
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
