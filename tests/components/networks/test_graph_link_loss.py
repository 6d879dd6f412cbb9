"""Network ``graph-link-loss``: links lost after the onset against numpy, delays scaled, and the
section's errors naming the field."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components.networks.delayed_graph import DelayedGraphNetwork
from formation_ftc.components.networks.graph import GraphNetwork, graph_edges
from formation_ftc.components.networks.graph_link_loss import (
    DelayedGraphLinkLossNetwork,
    GraphLinkLossNetwork,
)
from formation_ftc.config.loader import ScenarioError
from formation_ftc.core.history import history_init, history_push, required_capacity
from formation_ftc.sim.components import NetworkInputs, StepContext

C = np.array(
    [[0.0, 0.0, 0.5, 0.0], [0.6, 0.0, 0.0, 0.0], [0.0, 0.5, 0.0, 0.4], [0.6, 0.0, 0.0, 0.0]]
)
LOST = np.zeros((4, 4))
LOST[2, 3] = 1.0  # 3 <- 4
MSG = np.arange(12.0).reshape(4, 3) + 1.0


def _step(t, dt=1.0):
    """The step context of the step starting at ``t`` [s] (unit steps)."""
    return StepContext(round(float(t) / dt), jnp.asarray(t), dt)


def test_link_loss_delivers_zero_weight_after_onset_and_unchanged_before():
    net = GraphLinkLossNetwork(adjacency=C, lost=LOST, onset=np.asarray(50.0))
    healthy = GraphNetwork(adjacency=C)
    for t_k in (0.0, 49.0):
        got = net.receive(t_k, None, NetworkInputs(jnp.asarray(MSG), _step(t_k), None))
        want = healthy.receive(t_k, None, NetworkInputs(jnp.asarray(MSG), _step(t_k), None))
        for key in ("in_weight", "weighted_sum"):
            np.testing.assert_array_equal(np.asarray(got[key]), np.asarray(want[key]))
    got = net.receive(50.0, None, NetworkInputs(jnp.asarray(MSG), _step(50.0), None))
    c = C * (1.0 - LOST)  # numpy: receiver 3 now hears only spacecraft 2
    np.testing.assert_allclose(np.asarray(got["in_weight"]), c.sum(axis=1))
    np.testing.assert_allclose(np.asarray(got["weighted_sum"]), c @ MSG, rtol=1e-15)
    assert float(got["in_weight"][2]) == 0.5


def test_delayed_link_loss_drops_the_link_and_scales_the_delays():
    dt, T = 1.0, 2.0
    delays = tuple(tuple("2" for _ in range(4)) for _ in range(4))
    edges = graph_edges(C)
    cap = required_capacity(3 * T, dt) + 1
    base = dict(adjacency=C, delays=delays, edges=edges, capacity=cap)
    net = DelayedGraphLinkLossNetwork(
        **base, lost=LOST, onset=np.asarray(20.0), delay_scale=np.asarray(3.0)
    )
    healthy = DelayedGraphNetwork(**base)
    # messages m(t) = (t + 1) MSG pushed at t = 0 .. 30 s
    state = history_init(jnp.asarray(MSG), cap)
    for k in range(1, 31):
        state = history_push(state, jnp.asarray((k + 1.0) * MSG))
    t = 30.0
    ins = NetworkInputs(jnp.asarray(31.0 * MSG), _step(t), net.exogenous(jnp.asarray(t)))
    got = net.receive(t, state, ins)
    # after the onset: weights without 3 <- 4 and messages 3 T = 6 s old: m(24) = 25 MSG
    c = C * (1.0 - LOST)
    np.testing.assert_allclose(np.asarray(got["weighted_sum"]), c @ (25.0 * MSG), rtol=1e-12)
    np.testing.assert_allclose(np.asarray(got["in_weight"]), c.sum(axis=1))
    # before the onset the reading is the healthy network's (delay T = 2 s)
    t = 15.0
    state15 = history_init(jnp.asarray(MSG), cap)
    for k in range(1, 16):
        state15 = history_push(state15, jnp.asarray((k + 1.0) * MSG))
    ins = NetworkInputs(jnp.asarray(16.0 * MSG), _step(t), net.exogenous(jnp.asarray(t)))
    got, want = net.receive(t, state15, ins), healthy.receive(t, state15, ins)
    np.testing.assert_array_equal(np.asarray(got["weighted_sum"]), np.asarray(want["weighted_sum"]))
    np.testing.assert_allclose(np.asarray(want["weighted_sum"]), C @ (14.0 * MSG), rtol=1e-12)


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
    "network, needle",
    [
        ({"adjacency": [[0, 1], [1, 0]], "lost_links": [[1, 3]]}, "lost_links[0] = [1, 3]"),
        (
            {"adjacency": [[0, 0], [1, 0]], "lost_links": [[1, 2]]},
            "spacecraft 1 does not receive from 2",
        ),
        ({"adjacency": [[0, 1], [1, 0]], "delay_scale": 2.0}, "network.delay_scale"),
        ({"adjacency": [[0, 1], [1, 0]], "delays": [["1", "1"], ["1", "1"]]}, "max_delay"),
    ],
)
def test_catalog_rejects_bad_network_sections_naming_the_field(network, needle):
    with pytest.raises(ScenarioError) as err:
        ftc.load_scenario(_raw(network=network))
    assert needle in str(err.value)
