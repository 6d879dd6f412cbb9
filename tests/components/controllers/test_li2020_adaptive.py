"""Controller ``li2020-adaptive``: its kernels against the per-agent formulas of Li2020 eqs. (23)-(27),
Lemma 1 and the sigma forms (eqs. (13)-(16)); the law cannot see the truth; a loop without a reference
orbit is refused by ``ClosedLoop.validate`` naming both parts."""

from __future__ import annotations

import dataclasses
import inspect
import typing

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import formation_ftc as ftc
from formation_ftc.components.controllers.li2020_adaptive import (
    Li2020AdaptiveController,
    consensus,
    li2020_adaptation_rates,
    li2020_control,
    sigma_exponential,
    sigma_inverse_square,
)
from formation_ftc.components.networks.graph import GraphNetwork
from formation_ftc.config import loader
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import FlightInputs, NetworkInputs, StepContext

TRUTH_FIELDS = {"state", "true_state", "fault", "faults", "disturbance", "force", "process_noise"}

rng = np.random.default_rng(3)


def test_control_law_matches_per_agent_formula():
    """Vector form of E000-05 against a per-agent loop written from eqs. (23)-(27)."""
    N = 4
    s, Y = rng.normal(size=(N, 3)), rng.normal(size=(N, 3))
    C = np.array([[0, 0, 0.5, 0], [0.6, 0, 0, 0], [0, 0.5, 0, 0.4], [0.6, 0, 0, 0]])
    m_hat, beta, d_hat = rng.uniform(90, 110, N), rng.uniform(1, 10, N), rng.uniform(0.1, 5, N)
    sig, lam = 0.7, 20.0
    cons = consensus(
        GraphNetwork(adjacency=jnp.asarray(C)).receive(
            0.0, None, NetworkInputs(s, StepContext(0, 0.0, 0.1), None)
        ),
        s,
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


def _other_truth(loop):
    """The same loop with different true faults, disturbance and masses (truth side only)."""
    act = dataclasses.replace(
        loop.actuator, effectiveness=("0.3", "0.5", "0.7"), bias=("3", "-2", "1")
    )
    plant = dataclasses.replace(
        loop.plant, mass=loop.plant.mass * 1.7, disturbance_force=("5", "5*t", "-5")
    )
    return dataclasses.replace(loop, actuator=act, plant=plant)


@pytest.mark.parametrize("name", ["li2020-thm1", "li2020-thm2-delays"])
def test_controller_cannot_see_the_truth(name):
    """The controller's inputs are FlightInputs (no truth fields); with identical flight inputs its
    command is unchanged when the plant's masses / disturbance and the actuator's faults change,
    while the applied force does change."""
    cls = Li2020AdaptiveController
    hints = typing.get_type_hints(
        cls.output, globalns=vars(inspect.getmodule(cls)) | {"FlightInputs": FlightInputs}
    )
    assert hints["inputs"] is FlightInputs
    assert not TRUTH_FIELDS & set(FlightInputs._fields)
    loop = make_loop(
        ftc.load_scenario(name, {"simulation.horizon": 1.0, "simulation.record_every": 1})
    )
    assert isinstance(loop.controller, cls)
    other = _other_truth(loop)
    k = jnp.asarray(3, dtype=jnp.int64)
    state = loop.initial_state()  # same true state, hence the same measurement, in both loops
    step = jax.jit(lambda lp, st: lp.step(k, st)[1])
    out_a, out_b = step(loop, state), step(other, state)
    np.testing.assert_array_equal(np.asarray(out_a["command"]), np.asarray(out_b["command"]))
    assert np.max(np.abs(np.asarray(out_a["applied"]) - np.asarray(out_b["applied"]))) > 1e-3


def test_section_fields_are_the_controller_fields():
    """The TOML path is the pytree path: ``mu`` is the d_hat gain mu_i, ``orbit_mu`` the on-board
    gravitational parameter, ``formation.centre_offset`` the formation's."""
    raw, _ = loader.read_raw("compose-li2020-on-cw")
    raw["controller"].update(mu=[1.0, 2.0, 3.0, 4.0], orbit_mu=3.9e14)
    raw["controller"]["formation"]["centre_offset"] = [1.0, 2.0, 3.0]
    loop = make_loop(loader.validate(raw, "li2020"))
    np.testing.assert_array_equal(loop.controller.mu, [1.0, 2.0, 3.0, 4.0])
    assert float(loop.controller.orbit_mu) == 3.9e14
    np.testing.assert_array_equal(loop.controller.formation.centre_offset, [1.0, 2.0, 3.0])


def test_a_loop_without_a_reference_orbit_is_refused():
    """The law forms the natural acceleration of Y_i (eq. (8)) from the reference orbit known on
    board: without a [reference] the loop is refused naming the law, what it needs and who provides
    it (a CW plant needs no reference itself)."""
    raw, _ = loader.read_raw("compose-li2020-on-cw")
    del raw["reference"]
    with pytest.raises(
        loader.ScenarioError,
        match=r"controller li2020-adaptive needs a reference orbit known on board to form the "
        r"natural acceleration.*provided by: a \[reference\] section",
    ):
        loader.validate(raw, "li2020")
