"""Controller kernels of Li2020 (Thm 1/2) and SIR-FTC against their defining formulas."""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import formation_ftc  # noqa: F401
from formation_ftc.blocks.controllers.li2020_adaptive import (
    li2020_adaptation_rates,
    li2020_control,
    sigma_exponential,
    sigma_inverse_square,
)
from formation_ftc.blocks.controllers.sir_ftc import sir_epsilon, sir_ftc_control, sir_ftc_rate
from formation_ftc.components.controllers.li2020_adaptive import consensus
from formation_ftc.components.networks.weighted_graph import (
    DelayedGraphNetwork,
    GraphNetwork,
    graph_edges,
)
from formation_ftc.core.history import history_init, history_push
from formation_ftc.sim.components import NetworkInputs

rng = np.random.default_rng(3)


def test_control_law_matches_per_agent_formula():
    """Vector form of E000-05 against a per-agent loop written from eqs. (23)-(27)."""
    N = 4
    s, Y = rng.normal(size=(N, 3)), rng.normal(size=(N, 3))
    C = np.array([[0, 0, 0.5, 0], [0.6, 0, 0, 0], [0, 0.5, 0, 0.4], [0.6, 0, 0, 0]])
    m_hat, beta, d_hat = rng.uniform(90, 110, N), rng.uniform(1, 10, N), rng.uniform(0.1, 5, N)
    sig, lam = 0.7, 20.0
    cons = consensus(
        GraphNetwork(weights=jnp.asarray(C)).receive(0.0, None, NetworkInputs(s, 0.0, None)), s
    )
    f, xi = li2020_control(s, Y, cons, m_hat, beta, d_hat, sig, lam)
    bd, md, dd = li2020_adaptation_rates(s, Y, xi, d_hat, sig, 0.1, 1.0, 1.0, 0.01)
    for i in range(N):
        c_i = sum(C[i, j] * (s[i] - s[j]) for j in range(N))
        xi_i = m_hat[i] * Y[i] + lam * s[i] + c_i + d_hat[i] * np.tanh(s[i] / sig)
        w = xi_i @ s[i]
        f_i = -(beta[i] ** 2) * xi_i * w / np.sqrt(beta[i] ** 2 * w**2 + sig**2)
        assert np.allclose(xi[i], xi_i, rtol=1e-13) and np.allclose(f[i], f_i, rtol=1e-13)
        assert np.isclose(bd[i], 0.1 * w) and np.isclose(md[i], s[i] @ Y[i])
        assert np.isclose(dd[i], -0.01 * sig * d_hat[i] + np.abs(s[i]).sum())


def test_delayed_consensus_reduces_to_undelayed():
    """A delayed network whose history holds the same message at every sample delivers what the
    instantaneous network delivers (interpolating between equal samples)."""
    s = rng.normal(size=(4, 3))
    C = rng.uniform(0, 1, (4, 4)) * (1 - np.eye(4))
    delays = tuple(tuple("0.5 + 0.1*i + 0.01*j" for _ in range(4)) for _ in range(4))
    net = DelayedGraphNetwork(
        weights=jnp.asarray(C), delays=delays, edges=graph_edges(C), capacity=80, dt=0.01
    )
    hist = history_init(jnp.asarray(s), 80)
    for _ in range(5):
        hist = history_push(hist, jnp.asarray(s))
    t = 0.043
    exo = net.exogenous(t)
    got = consensus(net.receive(t, hist, NetworkInputs(s, 0.04, exo)), s)
    want = consensus(
        GraphNetwork(weights=jnp.asarray(C)).receive(t, None, NetworkInputs(s, 0.04, None)), s
    )
    assert np.allclose(got, want, atol=1e-14)


def test_delayed_network_reads_interpolated_past():
    """m_j(t - T_ij(t)) with linear interpolation between stored samples, against a per-link formula."""
    N, dt = 3, 0.1
    C = np.array([[0, 0.5, 0.2], [0.3, 0, 0], [0, 0.7, 0]])
    delays = (("0", "0.25", "0.3 + 0.1*sin(t)"), ("0.15", "0", "0"), ("0", "0.2 + 0.01*t", "0"))
    net = DelayedGraphNetwork(
        weights=jnp.asarray(C), delays=delays, edges=graph_edges(C), capacity=8, dt=dt
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
        jnp.asarray(rng.normal(size=(N, 2))), t_k, net.exogenous(t)
    )  # every T > t - t_k
    for network in (net, dataclasses.replace(net, short_delays=False)):
        got = network.receive(t, hist, now)
        for i in range(N):
            want = sum(C[i, j] * past(j, t - T[(i, j)]) for j in range(N) if C[i, j] > 0)
            np.testing.assert_allclose(
                np.asarray(got["weighted_sum"][i]), want, rtol=1e-12, atol=1e-14
            )
        np.testing.assert_allclose(np.asarray(got["in_weight"]), C.sum(axis=1))


@settings(max_examples=50, deadline=None)
@given(w=st.floats(-1e3, 1e3), sigma=st.floats(1e-3, 10.0), beta=st.floats(0.1, 20.0))
def test_lemma1_bound_on_control_power(w, sigma, beta):
    """Lemma 1 / eq. (31): -s^T f = beta^2 w^2/sqrt(beta^2 w^2 + sigma^2) >= beta|w| - sigma."""
    xi = np.array([w, 0.0, 0.0])
    s = np.array([1.0, 0.0, 0.0])
    f, _ = li2020_control(
        jnp.asarray(s[None]),
        jnp.zeros((1, 3)),
        jnp.asarray(xi[None]),
        jnp.zeros(1),
        jnp.array([beta]),
        jnp.zeros(1),
        sigma,
        0.0,
    )
    power = -float(np.asarray(f)[0] @ s)
    assert power >= beta * abs(w) - sigma - 1e-9 * (1 + beta * abs(w))
    assert power <= beta * abs(w) + 1e-9 * (1 + beta * abs(w))


def test_dhat_sign_flag():
    s, Y = jnp.ones((1, 3)), jnp.zeros((1, 3))
    _, xp = li2020_control(
        s, Y, jnp.zeros((1, 3)), jnp.zeros(1), jnp.ones(1), jnp.ones(1), 1.0, 0.0, 1.0
    )
    _, xm = li2020_control(
        s, Y, jnp.zeros((1, 3)), jnp.zeros(1), jnp.ones(1), jnp.ones(1), 1.0, 0.0, -1.0
    )
    assert np.allclose(np.asarray(xp), np.tanh(1.0)) and np.allclose(np.asarray(xm), -np.tanh(1.0))


def test_sigma_forms_integrable():
    """eq. (15)/(16): int_0^inf exp(-a t) = 1/a, int_0^inf 1/(a (t+t0)^2) = 1/(a t0) (trapezoid truth)."""
    t = np.linspace(0, 2e5, 2_000_001)
    assert abs(np.trapezoid(np.asarray(sigma_exponential(t, 1e-3)), t) - 1e3) < 1e-2
    t2 = np.concatenate([np.linspace(0, 100, 1_000_001), np.linspace(100, 1e6, 1_000_001)[1:]])
    val = np.trapezoid(np.asarray(sigma_inverse_square(t2, 2.0, 1.0)), t2)
    assert abs(val - (1 / 2.0) * (1 - 1 / (1e6 + 1))) < 1e-4


def test_sir_ftc_formula():
    s = rng.normal(size=(4, 3))
    b = rng.uniform(0, 10, 4)
    eps = sir_epsilon(1.0, 1.0)
    assert eps == 0.5
    f = np.asarray(sir_ftc_control(s, b, 20.0, 1.0, eps))
    bd = np.asarray(sir_ftc_rate(s, b, 1.0, eps, 1.0, 10.0))
    for i in range(4):
        n = np.linalg.norm(s[i])
        assert np.allclose(f[i], -(20 + b[i] / (n + eps)) * s[i])
        assert np.isclose(bd[i], -b[i] + 10 * n**2 / (n + eps))
