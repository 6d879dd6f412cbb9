"""Inertial two-body translation of a spacecraft with control force and disturbance (Yang2013 eq. (1)).

State ``s = [R, V]`` (shape ``(..., 6)``) in the Earth-centred inertial frame F0: position R [m] and
velocity V [m/s]. Dynamics::

    R' = V,   M V' = -mu M R / |R|^3 + f + d            # Yang2013 eq. (1)

with mass M [kg], control force f [N], disturbance force d [N] (|d| <= d_bar) and the gravitational
parameter mu [m^3/s^2]. Pure ``jax.numpy``; integrate with :func:`formation_ftc.core.integrators.rk4_step`.
"""

from __future__ import annotations

import jax.numpy as jnp

from formation_ftc.core.orbit import MU_EARTH

__all__ = [
    "gravity_acceleration",
    "two_body_rhs",
    "specific_energy",
    "specific_angular_momentum",
]


def gravity_acceleration(R, mu: float = MU_EARTH):
    """Inverse-square gravitational acceleration ``-mu R / |R|^3`` [m/s^2], shape (..., 3)."""
    R = jnp.asarray(R)
    r = jnp.linalg.norm(R, axis=-1, keepdims=True)
    return -mu * R / r**3


def two_body_rhs(t, state, force=None, disturbance=None, mass: float = 1.0, mu: float = MU_EARTH):
    """Time derivative of ``[R, V]`` under eq. (1).

    Parameters
    ----------
    t : time [s] (unused; the model is autonomous)
    state : (..., 6) ``[R, V]`` [m, m/s]
    force, disturbance : (..., 3) control force f and disturbance d [N]; None means zero
    mass : spacecraft mass M [kg]
    mu : gravitational parameter [m^3/s^2]
    """
    state = jnp.asarray(state)
    R, V = state[..., :3], state[..., 3:]
    acc = gravity_acceleration(R, mu)
    if force is not None:
        acc = acc + jnp.asarray(force) / mass
    if disturbance is not None:
        acc = acc + jnp.asarray(disturbance) / mass
    return jnp.concatenate([V, acc], axis=-1)


def specific_energy(state, mu: float = MU_EARTH):
    """Specific orbital energy ``|V|^2/2 - mu/|R|`` [J/kg] (conserved without f and d)."""
    state = jnp.asarray(state)
    R, V = state[..., :3], state[..., 3:]
    return 0.5 * jnp.sum(V * V, axis=-1) - mu / jnp.linalg.norm(R, axis=-1)


def specific_angular_momentum(state):
    """``R x V`` [m^2/s] (conserved without f and d)."""
    state = jnp.asarray(state)
    return jnp.cross(state[..., :3], state[..., 3:])
