"""Double integrator with actuator gains (core.dynamics.double_integrator), Azizi2009 Sec. II.

Truths: the closed-form solution under constant acceleration, the Van Loan ZOH discretisation
(scipy expm) and RK4 with a held input (exact for a quadratic-in-time solution). Tolerances are
round-off level (1e-12 relative) because every method is exact for this model.
"""

import jax
import jax.numpy as jnp
import numpy as np

from formation_ftc.core.dynamics.double_integrator import DoubleIntegratorState, rhs, zoh_step
from formation_ftc.core.integrators import rk4_step, zoh_discretize


def _state(rng, shape=(4, 3)):
    return DoubleIntegratorState(
        jnp.asarray(rng.normal(size=shape) * 100), jnp.asarray(rng.normal(size=shape))
    )


def test_zoh_step_matches_closed_form_over_many_steps():
    rng = np.random.default_rng(0)
    x0 = _state(rng)
    u = jnp.asarray(rng.normal(size=(4, 3)))
    b = jnp.asarray([[1.0], [0.8], [1.0], [0.5]]) * jnp.ones((1, 3))
    d = 1e-5
    dt, n = 0.01, 250
    step = jax.jit(lambda x: zoh_step(x, u, b, d, dt))
    x = x0
    for _ in range(n):
        x = step(x)
    T = n * dt
    a = b * u + d
    np.testing.assert_allclose(x.r, x0.r + x0.v * T + 0.5 * a * T**2, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(x.v, x0.v + a * T, rtol=1e-12, atol=1e-12)


def test_zoh_step_equals_van_loan_discretisation():
    A = np.array([[0.0, 1.0], [0.0, 0.0]])
    b_gain = 0.8
    B = np.array([[0.0], [b_gain]])
    dt = 0.37
    Ad, Bd = zoh_discretize(A, B, dt)
    r0, v0, u = 3.0, -2.0, 1.7
    ref = Ad @ np.array([r0, v0]) + Bd[:, 0] * u
    x = zoh_step(DoubleIntegratorState(jnp.asarray(r0), jnp.asarray(v0)), u, b_gain, 0.0, dt)
    np.testing.assert_allclose([float(x.r), float(x.v)], ref, rtol=1e-13)


def test_rk4_with_held_input_equals_zoh_step():
    rng = np.random.default_rng(1)
    x0 = _state(rng)
    u = jnp.asarray(rng.normal(size=(4, 3)))
    b = jnp.asarray(rng.uniform(0.5, 1.0, size=(4, 3)))
    d = jnp.asarray(rng.normal(size=(4, 3)) * 1e-5)
    dt = 0.05
    ref = zoh_step(x0, u, b, d, dt)
    got = rk4_step(rhs, 0.0, x0, dt, u, b, d)
    np.testing.assert_allclose(got.r, ref.r, rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(got.v, ref.v, rtol=1e-13, atol=1e-12)


def test_dead_actuator_drifts_and_float64_vmap():
    x0 = DoubleIntegratorState(jnp.zeros((5, 4, 3)), jnp.ones((5, 4, 3)))
    out = jax.vmap(lambda x: zoh_step(x, 10.0, 0.0, 0.0, 2.0))(x0)
    assert out.r.dtype == jnp.float64
    np.testing.assert_allclose(out.r, 2.0)  # b = 0: the input has no effect
    np.testing.assert_allclose(out.v, 1.0)
