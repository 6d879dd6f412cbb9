"""Yang2013's translational law (``yang2013-translational``) by hand and reused on a Clohessy-Wiltshire
plant."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from formation_ftc.components.controllers._yang2013 import Yang2013TranslationalController
from formation_ftc.components.plants.clohessy_wiltshire import ClohessyWiltshirePlant
from formation_ftc.components.sensors.relative_state import RelativeStateSensors
from formation_ftc.sim.components import FlightInputs
from formation_ftc.sim.loop import ClosedLoop


def test_translational_law_by_hand_and_on_a_cw_plant():
    n = 2
    law = Yang2013TranslationalController(
        count=n,
        nominal_mass=jnp.array([10.0, 20.0]),
        K1=jnp.asarray(0.5),
        K2=jnp.asarray(0.8),
        desired_position=("10*i", "0.1*t**2", "0"),
    )
    y = jnp.array([[1.0, 2.0, 3.0, 0.1, 0.2, 0.3], [-1.0, 0.5, 0.0, 0.0, -0.1, 0.2]])
    t = 2.0
    f, _, _ = law.output(t, None, FlightInputs(y, None, None, None, law.exogenous(t), None, None))
    p_d = np.array([[10.0, 0.4, 0.0], [20.0, 0.4, 0.0]])
    v_d = np.array([[0.0, 0.4, 0.0]] * 2)
    a_d = np.array([[0.0, 0.2, 0.0]] * 2)
    m = np.array([[10.0], [20.0]])
    np.testing.assert_allclose(
        f, m * (a_d + 1.5 * (p_d - y[:, :3]) + 0.8 * (v_d - y[:, 3:])), rtol=1e-14
    )
    # reusable on another translational plant: CW deputies regulated to a fixed offset
    mass = jnp.array([10.0, 20.0])
    plant = ClohessyWiltshirePlant(
        mean_motion=jnp.asarray(0.0011),
        mass=mass,
        initial_state_lvlh=jnp.array([[5.0, 0, 0, 0, 0, 0], [0, -5.0, 0, 0, 0, 0]]),
    )
    law = Yang2013TranslationalController(
        count=n,
        nominal_mass=mass,
        K1=jnp.asarray(0.01),
        K2=jnp.asarray(0.5),
        desired_position=("10", "20", "0"),
    )
    loop = ClosedLoop(
        plant=plant,
        controller=law,
        sensors=RelativeStateSensors(count=n),
        dt=0.5,
        n_steps=200,
        record_every=200,
    ).validate()
    out = jax.jit(lambda p: p.run())(loop)
    pos = np.asarray(out["final"]["plant"]["q"][:, :3])
    # the residual CW drift the law does not cancel (2 n v, 3 n^2 x: < 4e-6 m/s^2 per m) leaves a
    # small steady offset; the law settles within 1 m of the target
    np.testing.assert_allclose(pos, [[10, 20, 0]] * 2, atol=1.0)
