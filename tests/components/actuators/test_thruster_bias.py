"""The thruster-bias fault profile (``thruster-bias``, Gui2022 Sec. 5) against its formula."""

import jax.numpy as jnp
import numpy as np

from formation_ftc.components.actuators.thruster_bias import ThrusterBiasFaultActuator
from formation_ftc.sim.components import ActuatorInputs


def test_thruster_bias_profile():
    act = ThrusterBiasFaultActuator(
        count=1,
        onset=jnp.asarray([[1.0, 2.0, 3.0]]),
        magnitude=jnp.asarray([[0.5, -0.1, 0.0]]),
        amplitude=jnp.asarray([[0.0, 0.0, 0.25]]),
        omega=jnp.asarray([[0.0, 0.0, 0.05]]),
        phase=jnp.asarray([[0.0, 0.0, np.pi / 4]]),
        decay_amplitude=jnp.asarray([[0.0, 0.0, -0.2]]),
        decay_rate=jnp.asarray([[0.0, 0.0, 0.1]]),
        decay_origin=jnp.asarray([[0.0, 0.0, 3.0]]),
    )
    for t in (0.5, 1.0, 2.5, 3.0, 10.0):
        F = np.asarray(act.exogenous(jnp.asarray(t))["F"])[0]
        want = [
            0.5 * (t >= 1),
            -0.1 * (t >= 2),
            (0.25 * np.sin(0.05 * t + np.pi / 4) - 0.2 * np.exp(-0.1 * (t - 3.0))) * (t >= 3),
        ]
        np.testing.assert_allclose(F, want, rtol=1e-14, atol=1e-16)
        u = np.array([[1.0, 2.0, 3.0]])
        applied = act.apply(t, jnp.asarray(u), ActuatorInputs(act.exogenous(jnp.asarray(t)), None))
        np.testing.assert_allclose(np.asarray(applied)[0], u[0] + want, rtol=1e-14)
