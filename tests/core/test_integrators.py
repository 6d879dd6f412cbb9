"""RK4 order on a closed-form problem and ZOH discretisation against a fine integration."""

import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg
from scipy.integrate import solve_ivp

from formation_ftc.core.integrators import euler_step, rk4_step, zoh_discretize


def _integrate(step, dt, T=2.0):
    x = {"a": jnp.array([1.0, 0.0])}

    def rhs(t, x):  # harmonic oscillator with forcing: closed form below
        p, v = x["a"]
        return {"a": jnp.array([v, -4.0 * p + jnp.cos(t)])}

    for k in range(round(T / dt)):
        x = step(rhs, k * dt, x, dt)
    return np.asarray(x["a"][0])


def _exact(T=2.0):
    # x'' + 4x = cos t, x(0)=1, x'(0)=0 -> x = (2/3) cos 2t + (1/3) cos t
    return 2 / 3 * np.cos(2 * T) + np.cos(T) / 3


def test_rk4_fourth_order():
    errs = [abs(_integrate(rk4_step, dt) - _exact()) for dt in (0.1, 0.05)]
    assert errs[0] / errs[1] == pytest.approx(16, rel=0.1)


def test_euler_first_order():
    errs = [abs(_integrate(euler_step, dt) - _exact()) for dt in (0.01, 0.005)]
    assert errs[0] / errs[1] == pytest.approx(2, rel=0.1)


def test_zoh_matches_integration_with_held_input():
    rng = np.random.default_rng(0)
    A = rng.normal(size=(4, 4))
    B = rng.normal(size=(4, 2))
    u = np.array([0.3, -1.2])
    x0 = rng.normal(size=4)
    dt = 0.37
    Ad, Bd = zoh_discretize(A, B, dt)
    np.testing.assert_allclose(Ad, scipy.linalg.expm(A * dt), rtol=1e-13)
    sol = solve_ivp(lambda t, x: A @ x + B @ u, (0, dt), x0, rtol=1e-13, atol=1e-13, method="DOP853")
    np.testing.assert_allclose(Ad @ x0 + Bd @ u, sol.y[:, -1], rtol=1e-10, atol=1e-12)


def test_staged_rk4_equals_rk4_with_inputs_inside_rhs():
    from formation_ftc.core.integrators import rk4_step_staged

    def u(t):
        return jnp.array([jnp.cos(0.7 * t), jnp.exp(-t)])

    def rhs_inside(t, x):
        return -x + u(t)

    def rhs_staged(t, x, ut):
        return -x + ut

    x = jnp.array([1.0, -2.0])
    t, dt = 0.3, 0.1
    a = rk4_step(rhs_inside, t, x, dt)
    b = rk4_step_staged(rhs_staged, t, x, dt, (u(t), u(t + dt / 2), u(t + dt)))
    np.testing.assert_allclose(a, b, rtol=1e-15, atol=1e-15)
