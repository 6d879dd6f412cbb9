"""Actuator ``fault-battery``: the component and its section.

Every kind is checked against the applied output computed by hand with numpy from the module's
definition (saturation first, then the fault on the faulty channel)."""

from __future__ import annotations

import tomllib
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import tomli_w

import formation_ftc as ftc
from formation_ftc.components.actuators.fault_battery import (
    FAULT_KINDS,
    FaultBatteryActuator,
    fault_kind_code,
)
from formation_ftc.config.loader import ScenarioError
from formation_ftc.sim.components import ActuatorInputs

N = 3
LIMIT = np.array([2.0, 1.5, np.inf])  # per spacecraft [N]
CMD = np.array([[3.0, -0.4, 0.1], [1.0, -2.5, 0.7], [5.0, -6.0, 0.2]])
SC, AX, ONSET = 2, 1, 10.0  # faulty channel (spacecraft 2, axis 1), onset [s]


def _actuator(kind: str, **kw) -> FaultBatteryActuator:
    leaves = dict(
        saturation=LIMIT,
        fault_kind=float(fault_kind_code(kind)),
        spacecraft=float(SC),
        axis=float(AX),
        onset=ONSET,
        effectiveness=0.3,
        bias=0.25,
        period=6.0,
        duty=0.5,
        rate=0.01,
        min_effectiveness=0.4,
    )
    leaves.update(kw)
    return FaultBatteryActuator(
        count=N, **{k: np.asarray(v, dtype=float) for k, v in leaves.items()}
    )


def _apply(act, t, cmd=CMD, state=None):
    exo = act.exogenous(jnp.asarray(t, dtype=jnp.float64))
    st = act.initial_state() if state is None else state
    return np.asarray(act.apply(t, jnp.asarray(cmd), ActuatorInputs(exo, st))), act.outputs(
        t, jnp.asarray(cmd), ActuatorInputs(exo, st)
    )


def _clipped(cmd=CMD):
    return np.clip(cmd, -LIMIT[:, None], LIMIT[:, None])


def _expected(gain, bias=0.0, cmd=CMD):
    out = _clipped(cmd)
    out[SC - 1, AX] = gain * out[SC - 1, AX] + bias
    return out


@pytest.mark.parametrize(
    "kind, gain, bias",
    [
        ("none", 1.0, 0.0),
        ("loss_of_effectiveness", 0.3, 0.0),
        ("bias", 1.0, 0.25),
        ("outage", 0.0, 0.0),
    ],
)
def test_constant_kinds_before_and_after_onset(kind, gain, bias):
    act = _actuator(kind)
    for t in (0.0, 9.99):
        y, out = _apply(act, t)
        np.testing.assert_array_equal(y, _clipped())  # saturation only before the onset
        assert float(out["fault_active"]) == 0.0
    for t in (10.0, 50.0):
        y, out = _apply(act, t)
        np.testing.assert_allclose(y, _expected(gain, bias), rtol=0, atol=1e-15)
        assert float(out["fault_active"]) == (0.0 if kind == "none" else 1.0)
        eff = np.ones((N, 3))
        eff[SC - 1, AX] = gain
        np.testing.assert_array_equal(np.asarray(out["effectiveness"]), eff)


def test_saturation_clips_each_axis_and_flags_the_spacecraft():
    y, out = _apply(_actuator("none"), 0.0)
    np.testing.assert_array_equal(y, [[2.0, -0.4, 0.1], [1.0, -1.5, 0.7], [5.0, -6.0, 0.2]])
    # spacecraft 1 (x beyond 2 N) and 2 (y beyond 1.5 N) at a limit; 3 is unsaturated (inf)
    np.testing.assert_array_equal(np.asarray(out["saturated"]), [1.0, 1.0, 0.0])
    y, out = _apply(_actuator("none"), 0.0, cmd=0.1 * CMD)
    np.testing.assert_array_equal(y, 0.1 * CMD)
    np.testing.assert_array_equal(np.asarray(out["saturated"]), [0.0, 0.0, 0.0])


def test_bias_acts_after_saturation():
    """The faulty channel's command (-2.5 N) is clipped to -1.5 N first, then the bias adds 0.25 N."""
    y, _ = _apply(_actuator("bias"), 20.0)
    assert y[SC - 1, AX] == pytest.approx(-1.25, abs=1e-15)


def test_intermittent_on_off_pattern():
    act = _actuator(
        "intermittent"
    )  # period 6 s, duty 0.5: on [10, 13), off [13, 16), on [16, 19) ...
    c = _clipped()[SC - 1, AX]
    for t, on in [
        (9.0, True),
        (10.0, True),
        (12.9, True),
        (13.0, False),
        (15.9, False),
        (16.0, True),
        (18.5, True),
        (19.5, False),
        (100.0, (100.0 - 10.0) % 6.0 < 3.0),
    ]:
        y, out = _apply(act, t)
        assert y[SC - 1, AX] == (c if on else 0.0), t
        assert float(np.asarray(out["effectiveness"])[SC - 1, AX]) == (1.0 if on else 0.0)
        np.testing.assert_array_equal(
            np.delete(y.ravel(), (SC - 1) * 3 + AX),
            np.delete(_clipped().ravel(), (SC - 1) * 3 + AX),
        )


@pytest.mark.parametrize(
    ("kind", "departure"),
    [
        ("loss_of_effectiveness", ONSET),  # departs at the onset
        ("degrading", ONSET),
        (
            "intermittent",
            ONSET + 3.0,
        ),  # the first on phase is nominal: departs at its first off phase
    ],
)
def test_the_fault_in_the_scores_starts_at_the_first_departure_from_nominal(kind, departure):
    """fault_active and fault_channel (what fdi-scores compares a detector with) rise when the actuator
    first departs from nominal: at the onset, but for an intermittent fault (on 3 s, off 3 s here) at
    its first off phase -- and they stay up through the later on phases."""
    act = _actuator(kind)
    for t in (ONSET - 1.0, ONSET, departure - 0.1, departure, departure + 3.5, departure + 50.0):
        _, out = _apply(act, t)
        up = t >= departure
        assert float(out["fault_active"]) == (1.0 if up else 0.0), (kind, t)
        channel = np.asarray(out["fault_channel"])
        assert channel[SC - 1, AX] == (1.0 if up else 0.0) and channel.sum() == (1.0 if up else 0.0)


def test_an_always_on_intermittent_fault_never_departs():
    act = _actuator("intermittent", duty=1.0)
    for t in (ONSET, ONSET + 100.0):
        y, out = _apply(act, t)
        assert float(out["fault_active"]) == 0.0
        np.testing.assert_array_equal(y, _clipped())


def test_degrading_ramp_and_floor():
    act = _actuator("degrading")  # g = max(0.4, 1 - 0.01 (t - 10)): floor reached at t = 70 s
    c = _clipped()[SC - 1, AX]
    for t in (0.0, 10.0, 30.0, 69.0, 70.0, 500.0):
        g = 1.0 if t < ONSET else max(0.4, 1.0 - 0.01 * (t - ONSET))
        y, out = _apply(act, t)
        assert y[SC - 1, AX] == pytest.approx(g * c, rel=1e-14)
        assert float(np.asarray(out["effectiveness"])[SC - 1, AX]) == pytest.approx(g, rel=1e-14)


def test_stuck_holds_the_value_at_onset_while_the_command_changes():
    act = _actuator("stuck")
    state = act.initial_state()
    inputs = lambda t, s: ActuatorInputs(act.exogenous(jnp.asarray(t)), s)  # noqa: E731
    commands = [
        0.4 * CMD * (1.0 + 0.1 * k) * (-1) ** k for k in range(6)
    ]  # channel within its limit
    frozen = None
    for k, t in enumerate(
        [8.0, 9.0, 10.0, 11.0, 12.0, 13.0]
    ):  # steps of 1 s; onset on the grid at 10 s
        y = np.asarray(act.apply(t, jnp.asarray(commands[k]), inputs(t, state)))
        if t < ONSET:
            np.testing.assert_array_equal(y, _clipped(commands[k]))
        elif (
            t == ONSET
        ):  # the onset step: the channel still passes its saturated command, which freezes
            frozen = _clipped(commands[k])[SC - 1, AX]
            np.testing.assert_array_equal(y, _clipped(commands[k]))
        else:
            assert y[SC - 1, AX] == frozen != _clipped(commands[k])[SC - 1, AX]
            other = np.ones((N, 3), bool)
            other[SC - 1, AX] = False
            np.testing.assert_array_equal(y[other], _clipped(commands[k])[other])
        state = act.update(t, state, jnp.asarray(commands[k]), inputs(t, state))
    assert frozen == pytest.approx(0.4 * 1.2 * -2.5)


def test_one_compilation_serves_every_kind():
    traces = []

    @jax.jit
    def applied(act, t, cmd):
        traces.append(1)
        return act.apply(t, cmd, ActuatorInputs(act.exogenous(t), act.initial_state()))

    outs = {
        kind: np.asarray(applied(_actuator(kind), jnp.asarray(20.0), jnp.asarray(CMD)))
        for kind in FAULT_KINDS
    }
    assert len(traces) == 1
    np.testing.assert_allclose(outs["loss_of_effectiveness"], _expected(0.3))
    np.testing.assert_allclose(outs["bias"], _expected(1.0, 0.25))
    np.testing.assert_allclose(outs["degrading"], _expected(0.9))
    # the channel and the saturation are leaves too
    other = applied(
        _actuator("outage", spacecraft=1.0, axis=0.0, saturation=np.full(N, 0.5)),
        jnp.asarray(20.0),
        jnp.asarray(CMD),
    )
    assert len(traces) == 1
    want = np.clip(CMD, -0.5, 0.5)
    want[0, 0] = 0.0
    np.testing.assert_array_equal(np.asarray(other), want)


def test_unknown_kind_name():
    with pytest.raises(ValueError, match="allowed: none, loss_of_effectiveness"):
        fault_kind_code("jammed")


# ------------------------------------------------------------------------------------------- catalog
def _raw(actuator=None, network=None, plant_count=2):
    raw = {
        "scenario": {"name": "battery", "method": "composed"},
        "simulation": {"horizon": 10.0, "dt": 0.1},
        "plant": {
            "type": "clohessy-wiltshire",
            "semi_major_axis": 7000e3,
            "mass": [10.0] * plant_count,
            "initial_position": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]][:plant_count],
        },
        "controller": {"type": "pd", "kp": 1.0, "kd": 1.0},
    }
    if actuator is not None:
        raw["actuator"] = {"type": "fault-battery", **actuator}
    if network is not None:
        raw["network"] = {"type": "graph-link-loss", **network}
    return raw


@pytest.mark.parametrize(
    "actuator, needle",
    [
        ({"kind": "jammed"}, "actuator.kind"),
        (
            {"kind": "jammed"},
            "allowed: none, loss_of_effectiveness, bias, stuck, outage, intermittent, degrading",
        ),
        ({"kind": "bias", "spacecraft": 3}, "actuator.spacecraft = 3: must be in 1..2"),
        ({"kind": "bias", "spacecraft": 0}, "actuator.spacecraft"),
        ({"kind": "bias", "axis": 3}, "actuator.axis"),
        ({"kind": "bias", "saturation": [1.0, 2.0, 3.0]}, "actuator.saturation"),
        ({"kind": "bias", "saturation": -1.0}, "actuator.saturation"),
        ({"kind": "intermittent", "duty": 1.5}, "actuator.duty"),
        ({"kind": "bias", "euler_allocation": True}, "quaternion"),
    ],
)
def test_catalog_rejects_bad_actuator_sections_naming_the_field(actuator, needle):
    with pytest.raises(ScenarioError) as err:
        ftc.load_scenario(_raw(actuator=actuator))
    assert needle in str(err.value)


def test_catalog_builds_leaves_not_static_fields():
    from formation_ftc.methods.composed import make_loop

    a = make_loop(
        ftc.load_scenario(
            _raw(
                actuator={
                    "kind": "stuck",
                    "spacecraft": 2,
                    "axis": 1,
                    "onset": 3.0,
                    "saturation": 4.0,
                }
            )
        )
    ).actuator
    b = make_loop(
        ftc.load_scenario(
            _raw(actuator={"kind": "degrading", "rate": 0.1, "saturation": [1.0, 2.0]})
        )
    ).actuator
    assert jax.tree_util.tree_structure(a) == jax.tree_util.tree_structure(b)
    assert (
        float(a.fault_kind) == FAULT_KINDS.index("stuck")
        and float(a.spacecraft) == 2.0
        and float(a.axis) == 1.0
    )
    np.testing.assert_array_equal(a.saturation, [4.0, 4.0])
    np.testing.assert_array_equal(b.saturation, [1.0, 2.0])
    c = make_loop(ftc.load_scenario(_raw(actuator={"kind": "none"}))).actuator
    np.testing.assert_array_equal(c.saturation, [np.inf, np.inf])


# -------------------------------------------------------------------------------------- end to end
def test_li2020_on_cw_with_a_loss_of_effectiveness_runs_and_records_the_switch(tmp_path: Path):
    src = Path(ftc.__file__).parent / "scenarios" / "compose-li2020-on-cw.toml"
    raw = tomllib.loads(src.read_text())
    raw["simulation"].update(horizon=20.0, record_every=100)  # dt 0.01 s: records every 1 s
    raw["actuator"] = {
        "type": "fault-battery",
        "kind": "loss_of_effectiveness",
        "spacecraft": 2,
        "axis": 0,
        "onset": 10.0,
        "effectiveness": 0.5,
    }
    raw["metrics"] = [m for m in raw["metrics"] if m["name"] != "max_position_error_after_1000s"]
    raw["metrics"].append(
        {"name": "saturated_fraction", "signal": "saturated", "reduce": "mean", "spacecraft": "max"}
    )
    path = tmp_path / "li2020-loe.toml"
    path.write_bytes(tomli_w.dumps(raw).encode())
    ds, metrics = ftc.simulate_with_metrics(ftc.load_scenario(path))
    t = ds.time.values
    eff = ds.effectiveness.values  # (time, spacecraft, axis)
    np.testing.assert_array_equal(eff[t < 10.0], 1.0)
    np.testing.assert_array_equal(eff[t >= 10.0][:, 1, 0], 0.5)
    np.testing.assert_array_equal(np.delete(eff[t >= 10.0].reshape(-1, 12), 3, axis=1), 1.0)
    np.testing.assert_array_equal(ds.fault_active.values, (t >= 10.0).astype(float))
    # the applied force on the faulty channel is half the command after the onset, equal before
    cmd, app = ds.command.values, ds.applied.values
    np.testing.assert_allclose(app[t >= 10.0][:, 1, 0], 0.5 * cmd[t >= 10.0][:, 1, 0], rtol=1e-14)
    np.testing.assert_array_equal(app[t < 10.0], cmd[t < 10.0])
    assert metrics["saturated_fraction"] == 0.0  # no limit given: never saturated
    assert all(np.isfinite(v) for v in metrics.values())


def test_stuck_in_a_closed_loop_freezes_the_applied_output_at_onset():
    """A sampled PD law on CW: after the onset the faulty channel applies the command of the onset step
    (clipped at the limit) while the command keeps changing; other channels apply the clipped command."""
    raw = _raw(
        actuator={"kind": "stuck", "spacecraft": 2, "axis": 0, "onset": 3.0, "saturation": 0.2}
    )
    raw["simulation"].update(horizon=8.0, dt=0.1, record_every=1)
    raw["controller"].update(kp=0.3, kd=1.0, mode="sampled")
    ds = ftc.simulate(ftc.load_scenario(raw))
    t, cmd, app = ds.time.values, ds.command.values, ds.applied.values
    clipped = np.clip(cmd, -0.2, 0.2)
    k0 = int(np.argmin(np.abs(t - 3.0)))
    after = t >= 3.0 - 1e-9
    np.testing.assert_array_equal(app[:, 1, 0][after], clipped[k0, 1, 0])
    assert np.ptp(cmd[after][:, 1, 0]) > 1e-3  # the command does change
    np.testing.assert_array_equal(app[~after], clipped[~after])
    other = np.ones(app.shape[1:], bool)
    other[1, 0] = False
    np.testing.assert_array_equal(app[:, other], clipped[:, other])
    np.testing.assert_array_equal(ds.effectiveness.values[after][:, 1, 0], 0.0)
    saturated = np.any(np.abs(cmd) >= 0.2, axis=-1)
    assert saturated.any() and not saturated.all()
    np.testing.assert_array_equal(ds.saturated.values, saturated.astype(float))


def test_euler_allocation_is_the_torque_allocation_then_saturation_and_fault():
    from formation_ftc.components.actuators.euler_torque_allocation import EulerTorqueAllocation
    from formation_ftc.core.euler_quaternion import quaternion_from_euler_zyx

    q = jnp.asarray(
        quaternion_from_euler_zyx(
            jnp.asarray([[0.3, -0.2, 0.5], [0.1, 0.4, -0.7], [0.0, 0.0, 0.0]])
        )
    )
    plant_state = {"q": q, "omega": jnp.zeros((N, 3))}
    tau_gen = jnp.asarray(0.1 * CMD)
    body = np.asarray(
        EulerTorqueAllocation().apply(0.0, tau_gen, ActuatorInputs(None, None, None, plant_state))
    )
    for kind in ("none", "loss_of_effectiveness"):
        act = _actuator(kind, saturation=np.full(N, 0.3))
        act = FaultBatteryActuator(
            **{**{f: getattr(act, f) for f in act.__dataclass_fields__}, "euler_allocation": True}
        )
        exo = act.exogenous(jnp.asarray(20.0))
        y = np.asarray(
            act.apply(20.0, tau_gen, ActuatorInputs(exo, act.initial_state(), None, plant_state))
        )
        want = np.clip(body, -0.3, 0.3)
        if kind != "none":
            want[SC - 1, AX] *= 0.3
        np.testing.assert_allclose(y, want, rtol=0, atol=1e-15)


def test_euler_law_on_the_quaternion_plant_accepts_the_battery_with_euler_allocation():
    from formation_ftc.methods.composed import make_loop

    raw = tomllib.loads(
        (Path(ftc.__file__).parent / "scenarios" / "compose-mehrabian-on-yang2013.toml").read_text()
    )
    raw.pop("estimator", None)  # the scripted FDI reports the euler-torque-allocation's own faults
    raw["actuator"] = {
        "type": "fault-battery",
        "kind": "bias",
        "bias": 0.1,
        "euler_allocation": True,
    }
    loop = make_loop(ftc.load_scenario(raw))
    act = loop.actuator
    assert isinstance(act, FaultBatteryActuator) and act.euler_allocation and act.units == "N m"
    raw["actuator"]["euler_allocation"] = False
    with pytest.raises(ScenarioError, match="euler_allocation = true"):
        ftc.load_scenario(raw)
