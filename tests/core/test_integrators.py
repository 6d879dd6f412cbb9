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
    sol = solve_ivp(
        lambda t, x: A @ x + B @ u, (0, dt), x0, rtol=1e-13, atol=1e-13, method="DOP853"
    )
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


def test_autonomous_stages_plus_staged_rk4_equal_joint_rk4():
    """An autonomous sub-state integrated ahead (its four stage values feeding the coupled state's
    stages) gives the same step as RK4 on the joint system: a pendulum angle driving a forced
    oscillator. Same floating-point operations, so equal to round-off (1e-14)."""
    from formation_ftc.core.integrators import rk4_autonomous_stages, rk4_step_staged

    def f_theta(th):
        return 1.3 + 0.4 * jnp.cos(th)

    def rhs_joint(t, s):
        th, x = s
        return (f_theta(th), jnp.array([x[1], -4.0 * x[0] - 0.1 * x[1] + jnp.sin(th) * (1 + t)]))

    def rhs_coupled(t, x, sin_th):
        return jnp.array([x[1], -4.0 * x[0] - 0.1 * x[1] + sin_th * (1 + t)])

    th0, x0 = jnp.asarray(0.2), jnp.array([1.0, -0.5])
    t, dt = 0.3, 0.05
    th_ref, x_ref = rk4_step(rhs_joint, t, (th0, x0), dt)
    th1, stages = rk4_autonomous_stages(f_theta, th0, dt)
    x1 = rk4_step_staged(rhs_coupled, t, x0, dt, tuple(jnp.sin(s) for s in stages))
    np.testing.assert_allclose(th1, th_ref, rtol=1e-14)
    np.testing.assert_allclose(x1, x_ref, rtol=1e-14, atol=1e-15)
    # and the stage values are those RK4 visits: y1 = y, y4 = y + dt k3 (4th-order accurate step)
    assert float(stages[0]) == float(th0)
    with pytest.raises(ValueError):
        rk4_step_staged(rhs_coupled, t, x0, dt, (1.0, 2.0))
