"""Composition: Li2020 Thm 2's time-varying delays on Yang2013's translational formation law
(``compose-li2020-delays-on-yang2013``: yang2013-relative, NeighbourRelativeController, DelayedGraphNetwork)."""

from __future__ import annotations

import copy
import tomllib
from importlib import resources

import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.cli import main
from formation_ftc.components.networks.delayed_graph import DelayedGraphNetwork
from formation_ftc.components.networks.graph import graph_edges
from formation_ftc.config.loader import ScenarioError
from formation_ftc.core.history import history_init, history_push
from formation_ftc.sim.components import NetworkInputs, StepContext, as_float

NAME = "compose-li2020-delays-on-yang2013"
SHORT = {"simulation.horizon": 40.0, "simulation.record_every": 1}


def _raw() -> dict:
    text = resources.files("formation_ftc.scenarios").joinpath(f"{NAME}.toml").read_text()
    raw = tomllib.loads(text)
    raw["simulation"].update(horizon=40.0, record_every=1)
    return raw


@pytest.fixture(scope="module")
def delayed():
    return ftc.simulate_with_metrics(ftc.load_scenario(NAME, SHORT))


def test_scenario_runs_records_metrics_and_check(delayed):
    ds, m = delayed
    for var in (
        "position",
        "position_error",
        "relative_formation_error",
        "referenced_formation_error",
        "command",
        "applied",
        "delta_v",
    ):
        assert var in ds, var
    assert ds.sizes["spacecraft"] == 4 and ds.sizes["time"] == 801
    assert np.isnan(m.pop("max_relative_error_after_500s"))  # window beyond this 40 s run
    assert all(np.isfinite(v) for k, v in m.items() if k != "scenario")
    assert all(c.holds for c in ftc.check(ftc.load_scenario(NAME, SHORT)))
    # spacecraft 2 follows the main spacecraft (on its slot): its error oscillates at ~1 rad/s and decays
    # as exp(-K2 t / 2); compare the envelope of the first and last 10 s
    e2 = np.linalg.norm(ds.relative_formation_error.values[:, 1], axis=-1)
    t = ds.time.values
    assert e2[t >= 30.0].max() < 0.9 * e2[t <= 10.0].max()


def test_received_errors_are_the_senders_errors_at_the_delayed_times(delayed):
    """Independent truth: spacecraft 3 references 2 and 4 (c_32 = 0.5, c_34 = 0.4) and must receive
    (0.5 eps_2(t - T_32(t)) + 0.4 eps_4(t - T_34(t))) / 0.9, eps_j = recorded position error,
    interpolated linearly in the records of every step (constant before t = 0)."""
    ds, _ = delayed
    t = ds.time.values
    eps = ds.position_error.values  # sensors are exact: eps_j = measured p_j - p^d_j
    T32 = 2 + 0.4 * np.sin(0.2 * t)
    T34 = 3 + 0.6 * np.sin(0.2 * t)
    expect = np.stack(
        [
            (0.5 * np.interp(t - T32, t, eps[:, 1, a]) + 0.4 * np.interp(t - T34, t, eps[:, 3, a]))
            / 0.9
            for a in range(3)
        ],
        axis=-1,
    )
    np.testing.assert_allclose(
        ds.referenced_formation_error.values[:, 2], expect, rtol=0, atol=1e-9
    )
    # spacecraft 1 (coupling 0) ignores what it receives: its regulated error is its own
    np.testing.assert_allclose(
        ds.relative_formation_error.values[:, 0], eps[:, 0], rtol=0, atol=1e-12
    )


def test_zero_delays_equal_the_undelayed_law_and_delays_change_the_result(delayed):
    ds_delayed, _ = delayed
    zero = _raw()
    zero["network"]["delays"] = [["0"] * 4 for _ in range(4)]
    instant = _raw()
    instant["network"] = {"type": "graph", "adjacency": instant["network"]["adjacency"]}
    ds0 = ftc.simulate(ftc.load_scenario(zero))
    ds_i = ftc.simulate(ftc.load_scenario(instant))
    for var in ("position", "velocity", "command", "referenced_formation_error"):
        np.testing.assert_allclose(
            ds0[var].values, ds_i[var].values, rtol=1e-12, atol=1e-12, err_msg=var
        )
    # the delays change where spacecraft 3 flies (it references 2 and 4 through 2-3.6 s delays) ...
    d3 = np.abs(ds_delayed.position.values[:, 2] - ds0.position.values[:, 2]).max()
    assert d3 > 1e-2
    # ... and nothing for the main spacecraft, which ignores what it receives
    np.testing.assert_allclose(
        ds_delayed.position.values[:, 0], ds0.position.values[:, 0], rtol=0, atol=1e-12
    )


def test_coupling_zero_is_the_plain_yang2013_law():
    """beta_i = 0 everywhere: every spacecraft tracks its own slot, exactly as the message-free law."""
    rel = _raw()
    rel["controller"]["coupling"] = 0.0
    plain = copy.deepcopy(rel)
    plain["controller"] = {k: v for k, v in plain["controller"].items() if k != "coupling"}
    plain["controller"]["type"] = "yang2013-translational"
    del plain["network"]
    plain["metrics"] = [m for m in plain["metrics"] if "relative" not in m["signal"]]
    a = ftc.simulate(ftc.load_scenario(rel))
    b = ftc.simulate(ftc.load_scenario(plain))
    np.testing.assert_allclose(a.position.values, b.position.values, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(a.command.values, b.command.values, rtol=1e-12, atol=1e-12)


def test_delayed_graph_reads_interpolate_toward_the_message_sent_now():
    """Delays shorter than the elapsed part of the step: linear between m(t_k) and the message m(t)."""
    C = [[0.0, 1.0], [0.0, 0.0]]
    net = DelayedGraphNetwork(
        adjacency=as_float(C),
        delays=(("0", "0.1"), ("0", "0")),
        edges=graph_edges(C),
        capacity=4,
    )
    h = history_push(
        history_init(jnp.array([[0.0], [1.0]]), 4), jnp.array([[0.0], [2.0]])
    )  # m_2(t_k) = 2
    now = jnp.array([[0.0], [6.0]])  # m_2(t) = 6 at t = t_k + 0.08
    for T, want in ((0.0, 6.0), (0.02, 5.0), (0.08, 2.0), (0.13, 1.5)):
        got = net.receive(
            jnp.asarray(1.08),
            h,
            NetworkInputs(now, StepContext(10, jnp.asarray(1.0), 0.1), {"T": jnp.array([T])}),
        )
        np.testing.assert_allclose(float(got["weighted_sum"][0, 0]), want, rtol=1e-12)


@pytest.mark.parametrize(
    "controller, network, needles",
    [
        (
            {"type": "yang2013-translational"},
            True,
            ("network delayed-graph", "controller yang2013-translational"),
        ),
        ({"type": "yang2013-relative"}, False, ("yang2013-relative", "[network]")),
        ({"type": "yang2013-relative", "coupling": 1.5}, True, ("coupling", "[0, 1]")),
    ],
)
def test_impossible_compositions_are_rejected_at_validation(controller, network, needles):
    raw = _raw()
    raw["controller"] = {
        **{k: v for k, v in raw["controller"].items() if k not in ("type", "coupling")},
        **controller,
    }
    if not network:
        del raw["network"]
    with pytest.raises(ScenarioError) as err:
        ftc.load_scenario(raw)
    for needle in needles:
        assert needle in str(err.value), (needle, str(err.value))


def test_cli_rejects_the_delayed_network_with_the_message_free_law_exit_2(tmp_path, capsys):
    text = resources.files("formation_ftc.scenarios").joinpath(f"{NAME}.toml").read_text()
    text = text.replace('type = "yang2013-relative"', 'type = "yang2013-translational"')
    text = "\n".join(line for line in text.splitlines() if not line.startswith("coupling"))
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "network delayed-graph" in err and "controller yang2013-translational" in err
