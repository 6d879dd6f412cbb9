"""Gui2022's plant (``clohessy-wiltshire-zoh``): the exact ZOH step and the perturbation d(t) against
scipy and the formula of Gui2022's ref. [12]."""

import jax.numpy as jnp
import numpy as np

from formation_ftc.components.plants.clohessy_wiltshire_zoh import ZohClohessyWiltshirePlant
from formation_ftc.core.dynamics.cw import cw_matrices
from formation_ftc.core.integrators import zoh_discretize
from formation_ftc.sim.components import TruthInputs


def test_exact_cw_step_matches_scipy_zoh():
    n, dt = 0.0011, 0.5
    rng = np.random.default_rng(3)
    q0, u = rng.normal(size=(2, 6)) * [100, 100, 100, 0.1, 0.1, 0.1], rng.normal(size=(2, 3)) * 1e-3
    plant = ZohClohessyWiltshirePlant(
        mean_motion=jnp.asarray(n),
        initial_state_lvlh=jnp.asarray(q0),
        disturbance_amplitude=jnp.asarray(2e-4),
    )
    t = 123.0
    d = plant.exogenous(jnp.asarray(t))["d"]
    nt = n * t
    d_ref = 2e-4 * np.array([1 - 1.5 * np.sin(nt), 0.5 * np.sin(2 * nt), np.sin(nt)])
    np.testing.assert_allclose(d, np.broadcast_to(d_ref, (2, 3)), rtol=1e-13, atol=1e-20)
    got = plant.prepare(dt).exact_step(
        t, {"q": jnp.asarray(q0)}, TruthInputs(jnp.asarray(u), {"d": d}, None, None), dt
    )["q"]
    A, B = cw_matrices(n)
    Ad, Bd = zoh_discretize(A, B, dt)
    want = q0 @ Ad.T + (u + d_ref) @ Bd.T
    np.testing.assert_allclose(np.asarray(got), want, rtol=1e-12, atol=1e-12)
    # without prepare() the step computes the discretisation itself
    got2 = plant.exact_step(
        t, {"q": jnp.asarray(q0)}, TruthInputs(jnp.asarray(u), {"d": d}, None, None), dt
    )
    np.testing.assert_allclose(np.asarray(got2["q"]), want, rtol=1e-12, atol=1e-12)
