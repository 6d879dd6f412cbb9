"""Actuator fault vocabulary (pure functions).

A fault maps the commanded input ``u`` to the applied input. All maps act element-wise on arrays of
shape (..., m) and are differentiable where the physics is.

* :func:`loss_of_effectiveness` -- multiplicative Gamma(t) u (Li2020 eq. (5), Azizi b_i)
* :func:`additive_bias` -- u + delta(t) (Li2020 delta_i, Gui2022 F(t), Mehrabian u_bar)
* :func:`lock_in_place` -- actuator frozen at the value it had at onset
* :func:`intermittent` -- a fault active only on windows [on_k, off_k)
* :func:`actuator_fault` -- the composition Gamma u + delta used by most papers
* :func:`controller_gain_fault` -- a gain that changes from K to K_f at onset (Yang2013 K2 -> K2f)
"""

from __future__ import annotations

import jax.numpy as jnp

__all__ = [
    "loss_of_effectiveness",
    "additive_bias",
    "lock_in_place",
    "intermittent",
    "actuator_fault",
    "controller_gain_fault",
]


def loss_of_effectiveness(u, effectiveness):
    """Applied input Gamma u with Gamma = diag(effectiveness), 0 < effectiveness <= 1."""
    return effectiveness * u


def additive_bias(u, bias):
    """Applied input u + bias."""
    return u + bias


def lock_in_place(u, locked_value, locked):
    """Where ``locked`` (bool per channel) the applied input is ``locked_value``, else ``u``."""
    return jnp.where(locked, locked_value, u)


def intermittent(t, windows):
    """1.0 when t lies in one of the [on, off) windows (array of shape (k, 2)), else 0.0."""
    windows = jnp.asarray(windows, dtype=jnp.float64).reshape(-1, 2)
    inside = (t >= windows[:, 0]) & (t < windows[:, 1])
    return jnp.where(jnp.any(inside), 1.0, 0.0)


def actuator_fault(u, effectiveness, bias):
    """F = Gamma u + delta (Li2020 eq. (5))."""
    return effectiveness * u + bias


def controller_gain_fault(t, nominal_gain, faulty_gain, onset):
    """Gain K for t < onset, K_f for t >= onset."""
    return jnp.where(t >= onset, faulty_gain, nominal_gain)
