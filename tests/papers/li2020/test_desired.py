"""Desired formation geometry and constants (SPEC P0.6-3/4), exact derivatives (autodiff truth)."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from formation_ftc.components.evaluations.li2020_formation_errors import (
    mu1,
    mu2_literal,
    mu2_virtual_centre,
    settle_time,
)
from formation_ftc.core.rotating_formation import (
    chi_from_period,
    desired_trajectory,
    formation_offsets,
)
from formation_ftc.methods.composed import make_loop


def _formation(scn):
    """(rho0 (N, 3), desired-trajectory arguments) of the scenario's closed loop."""
    loop = make_loop(scn)
    f = loop.controller.formation
    return np.asarray(loop.plant.initial_state_lvlh)[:, :3], (
        f.offsets,
        f.chi,
        f.rotation,
        f.growth,
        f.centre_offset,
    )


def test_constants(load):
    """n_c, T_c, chi to rel. 1e-5; g(T_c/2) = 1 - 1e-6 (E000-09)."""
    scn = load("li2020-thm1")
    orbit = scn.section("reference")
    n = math.sqrt(orbit.mu / orbit.semi_major_axis**3)
    T = scn.section("controller").formation.period
    assert abs(n / 1.078008e-3 - 1) < 1e-5 and abs(T / 5828.52 - 1) < 1e-5
    assert T == 2 * math.pi / n  # the stated period is the reference orbit's, to the last bit
    chi = chi_from_period(T)
    assert abs(chi / 3.07368e5 - 1) < 1e-5
    assert abs(float(make_loop(scn).controller.formation.chi) - chi) < 1e-9
    g = 1 - math.exp(-((T / 2) ** 2) / (2 * chi))
    assert abs((1 - g) - 1e-6) < 1e-12


def test_initial_geometry(load):
    """e_i1(0), mu1(0) = 18.127 m, edges 707.11 m, diagonals 1000 m (x1.6 after the maneuver),
    literal mu2 at the desired shape = 0, mu2_vc(0) = 171.38 m."""
    scn = load("li2020-thm1")
    rho0, args = _formation(scn)
    rd0, vd0, _, rf0 = desired_trajectory(0.0, *args)
    e1 = rho0 - np.asarray(rd0)
    want = np.array([[0, 20, -10.013], [-15, -5, 10], [12, -10, 0], [5, 0, 15]])
    assert np.allclose(e1, want, atol=1e-3)
    assert abs(float(mu1(e1)) - 18.127) < 1e-3
    assert np.allclose(np.asarray(vd0), 0.0)
    d = np.linalg.norm(np.asarray(rd0)[:, None] - np.asarray(rd0)[None], axis=-1)
    assert np.allclose([d[0, 1], d[1, 2], d[2, 3], d[3, 0]], 500 * math.sqrt(2), atol=1e-9)
    assert np.allclose([d[0, 2], d[1, 3]], 1000.0, atol=1e-9)
    rdT = np.asarray(desired_trajectory(1e6, *args)[0])
    dT = np.linalg.norm(rdT[:, None] - rdT[None], axis=-1)
    assert np.allclose([dT[0, 2], dT[1, 3]], 1600.0, atol=1e-6)
    for t in (0.0, 500.0, 3000.0):
        assert float(mu2_literal(desired_trajectory(t, *args)[0])) < 1e-9
    assert abs(float(mu2_virtual_centre(rho0, rf0)) - 171.38) < 5e-3


def test_velocity_and_acceleration_are_exact_derivatives(load):
    """v^d = d rho^d/dt and a^d = d v^d/dt (forward-mode autodiff of the position as the truth)."""
    _, args = _formation(load("li2020-thm1"))
    pos = lambda t: desired_trajectory(t, *args)[0]  # noqa: E731
    vel = lambda t: desired_trajectory(t, *args)[1]  # noqa: E731
    for t in (0.0, 137.0, 900.0, 2914.0):
        _, v_ad = jax.jvp(pos, (jnp.asarray(t),), (jnp.asarray(1.0),))
        _, a_ad = jax.jvp(vel, (jnp.asarray(t),), (jnp.asarray(1.0),))
        r, v, a, _ = desired_trajectory(t, *args)
        assert np.allclose(v, v_ad, rtol=1e-12, atol=1e-15)
        assert np.allclose(a, a_ad, rtol=1e-12, atol=1e-18)


def test_formation_offsets_sign_pattern():
    """E000-10: rho_bar_iF = R [cos/2, -sin, sqrt(3)/2 cos]."""
    rb = formation_offsets(500.0, [0, math.pi / 2, math.pi, 3 * math.pi / 2])
    assert np.allclose(
        rb, [[250, 0, 433.0127], [0, -500, 0], [-250, 0, -433.0127], [0, 500, 0]], atol=1e-4
    )


def test_settle_time():
    t = np.arange(6.0)
    assert settle_time(t, np.array([5, 2, 0.5, 1.5, 0.2, 0.1]), 1.0) == 4.0
    assert math.isnan(settle_time(t, np.array([5, 2, 0.5, 0.5, 0.2, 3]), 1.0))
    assert settle_time(t, np.zeros(6), 1.0) == 0.0
