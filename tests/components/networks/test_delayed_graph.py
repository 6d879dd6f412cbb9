"""Network ``delayed-graph`` (and ``graph``): the delayed reads against the instantaneous graph and a
per-link interpolation formula (Li2020 eq. (42))."""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp
import numpy as np

from formation_ftc.components.controllers.li2020_adaptive import consensus
from formation_ftc.components.networks.delayed_graph import DelayedGraphNetwork
from formation_ftc.components.networks.graph import GraphNetwork, graph_edges
from formation_ftc.core.history import history_init, history_push
from formation_ftc.sim.components import NetworkInputs, StepContext

rng = np.random.default_rng(3)


def test_delayed_consensus_reduces_to_undelayed():
    """A delayed network whose history holds the same message at every sample delivers what the
    instantaneous network delivers (interpolating between equal samples)."""
    s = rng.normal(size=(4, 3))
    C = rng.uniform(0, 1, (4, 4)) * (1 - np.eye(4))
    delays = tuple(tuple("0.5 + 0.1*i + 0.01*j" for _ in range(4)) for _ in range(4))
    net = DelayedGraphNetwork(
        adjacency=jnp.asarray(C), delays=delays, edges=graph_edges(C), capacity=80
    )
    hist = history_init(jnp.asarray(s), 80)
    for _ in range(5):
        hist = history_push(hist, jnp.asarray(s))
    t = 0.043
    exo = net.exogenous(t)
    got = consensus(net.receive(t, hist, NetworkInputs(s, StepContext(4, 0.04, 0.01), exo)), s)
    want = consensus(
        GraphNetwork(adjacency=jnp.asarray(C)).receive(
            t, None, NetworkInputs(s, StepContext(4, 0.04, 0.01), None)
        ),
        s,
    )
    assert np.allclose(got, want, atol=1e-14)


def test_delayed_network_reads_interpolated_past():
    """m_j(t - T_ij(t)) with linear interpolation between stored samples, against a per-link formula."""
    N, dt = 3, 0.1
    C = np.array([[0, 0.5, 0.2], [0.3, 0, 0], [0, 0.7, 0]])
    delays = (("0", "0.25", "0.3 + 0.1*sin(t)"), ("0.15", "0", "0"), ("0", "0.2 + 0.01*t", "0"))
    net = DelayedGraphNetwork(
        adjacency=jnp.asarray(C), delays=delays, edges=graph_edges(C), capacity=8
    )
    samples = [rng.normal(size=(N, 2)) for _ in range(6)]  # m(t_0) .. m(t_5), t_k = k dt
    hist = history_init(jnp.asarray(samples[0]), 8)
    for m in samples[1:]:
        hist = history_push(hist, jnp.asarray(m))
    t_k, t = 0.5, 0.53

    def past(j, tau):  # linear interpolation of sender j at time tau
        x = tau / dt
        k0 = int(np.floor(x))
        w = x - k0
        return (1 - w) * samples[k0][j] + w * samples[k0 + 1][j]

    T = {(0, 1): 0.25, (0, 2): 0.3 + 0.1 * np.sin(t), (1, 0): 0.15, (2, 1): 0.2 + 0.01 * t}
    now = NetworkInputs(
        jnp.asarray(rng.normal(size=(N, 2))), StepContext(5, t_k, dt), net.exogenous(t)
    )  # every T > t - t_k
    for network in (net, dataclasses.replace(net, short_delays=False)):
        got = network.receive(t, hist, now)
        for i in range(N):
            want = sum(C[i, j] * past(j, t - T[(i, j)]) for j in range(N) if C[i, j] > 0)
            np.testing.assert_allclose(
                np.asarray(got["weighted_sum"][i]), want, rtol=1e-12, atol=1e-14
            )
        np.testing.assert_allclose(np.asarray(got["in_weight"]), C.sum(axis=1))
