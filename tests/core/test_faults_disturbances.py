"""Fault and disturbance vocabulary and the shared time functions against closed forms."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from formation_ftc.core import disturbances, faults, timefunctions


def test_actuator_fault_composition():
    u = jnp.array([[1.0, -2.0, 3.0]])
    gam = jnp.array([[0.5, 1.0, 0.2]])
    delta = jnp.array([[0.1, 0.0, -0.1]])
    np.testing.assert_allclose(faults.actuator_fault(u, gam, delta), [[0.6, -2.0, 0.5]])
    np.testing.assert_allclose(
        faults.additive_bias(faults.loss_of_effectiveness(u, gam), delta),
        faults.actuator_fault(u, gam, delta),
    )


def test_lock_in_place_and_intermittent():
    u = jnp.array([1.0, 2.0, 3.0])
    out = faults.lock_in_place(u, jnp.array([9.0, 9.0, 9.0]), jnp.array([False, True, False]))
    np.testing.assert_allclose(out, [1.0, 9.0, 3.0])
    win = [[10.0, 20.0], [30.0, 31.0]]
    vals = [float(faults.intermittent(t, win)) for t in (9.9, 10.0, 19.99, 20.0, 30.5, 31.0)]
    assert vals == [0.0, 1.0, 1.0, 0.0, 1.0, 0.0]


def test_controller_gain_fault():
    k = faults.controller_gain_fault(jnp.array([3799.95, 3800.0]), 0.01, -0.01, 3800.0)
    np.testing.assert_allclose(k, [0.01, -0.01])


def test_time_functions():
    t = jnp.array([0.0, 9.0, 10.0, 15.0])
    np.testing.assert_allclose(timefunctions.step(t, 10.0, 0.5), [0, 0, 0.5, 0.5])
    np.testing.assert_allclose(timefunctions.window(t, 9.0, 10.0, 2.0), [0, 2, 2, 0])
    loe = timefunctions.exp_recovery_loe(t, 10.0, 0.3, 0.5)
    np.testing.assert_allclose(loe, [1, 1, 0.7, 1 - 0.3 * np.exp(-2.5)])
    np.testing.assert_allclose(
        timefunctions.sinusoid(2.0, 0.05, 0.02, 0.0, 0.6), 0.6 + 0.05 * np.sin(0.04)
    )


def test_smooth_transition_derivatives_by_autodiff():
    chi = 3.07368e5
    g = lambda t: timefunctions.smooth_transition(t, chi)[0]  # noqa: E731
    for t in (0.0, 500.0, 2914.0):
        _, gd, gdd = timefunctions.smooth_transition(t, chi)
        assert float(jax.grad(g)(t)) == pytest.approx(float(gd), rel=1e-12, abs=1e-18)
        assert float(jax.grad(jax.grad(g))(t)) == pytest.approx(float(gdd), rel=1e-10, abs=1e-18)
    # SPEC P0.6-3: g(T_c/2) = 1 - 1e-6
    assert float(g(5828.516637686015 / 2)) == pytest.approx(1 - 1e-6, abs=1e-9)


def test_gaussian_noise_is_seeded_and_has_the_right_moments():
    key = disturbances.run_key(7)
    a = disturbances.gaussian_noise(disturbances.step_key(key, 3), (20000,), 0.0316)
    b = disturbances.gaussian_noise(disturbances.step_key(key, 3), (20000,), 0.0316)
    c = disturbances.gaussian_noise(disturbances.step_key(key, 4), (20000,), 0.0316)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    assert a.dtype == jnp.float64
    # variance 0.001 within 5 standard errors (SE of the variance ~ sigma^2 sqrt(2/n))
    assert abs(float(jnp.var(a)) - 0.0316**2) < 5 * 0.0316**2 * np.sqrt(2 / 20000)
    assert abs(float(jnp.mean(a))) < 5 * 0.0316 / np.sqrt(20000)


def test_sinusoidal_disturbance_bound():
    t = jnp.linspace(0, 1000, 10001)
    d = disturbances.sinusoidal(t, 0.06, 1.0, 0.3)
    assert float(jnp.max(jnp.abs(d))) <= 0.06 + 1e-15
