"""Learning output-feedback fault-tolerant tracking controller (LOF2TC), Gui et al. 2022 eqs. (30)-(32).

With the tracking error ``e_q = q0 - q`` and ``e_y = C e_q`` (29)::

    pi(t) = G1 pi(t - tau) + G2 e_q^T (K C)^T (K C) e_q                 # (31), uses K C e_q = K e_y
    v(t)  = G3 v(t - tau) + G4 K e_q(t)                                 # (32), K e_q := K e_y (C = I)
    u     = pi(t) K e_y - B^+ E v(t) - B^+ H F_hat(t)                   # (30)

``F_hat`` comes from the iterative learning observer (5). Discrete implementation: the
learning laws are recursions evaluated once per sample with ``tau = m dt`` (m integer >= 1); the caller
keeps the past values (:mod:`formation_ftc.core.delay_line`; prehistory ``pi(-tau) = pi_init``
[CHOICE, E002-08: so that pi >= 1/2 initially], ``v(-tau) = v_init``).

Every function acts on the last axis and broadcasts over leading axes (one row per spacecraft).
Units: e_y in [m, m/s], K in [1/s^2, 1/s], u, v, F_hat in m/s^2 (per unit mass, E002-03), pi [-];
``G1`` [-], ``G2`` [s^4/m^2] (so that pi is dimensionless), ``G3`` (m,) diagonal [-], ``G4`` [-],
``BpE`` = B^+ E and ``BpH`` = B^+ H (m, m).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from formation_ftc.core.linear import matvec

__all__ = ["lof2tc_law"]


def lof2tc_law(
    e_y: jax.Array,
    F_hat: jax.Array,
    pi_past: jax.Array,
    v_past: jax.Array,
    K,
    G1,
    G2,
    G3,
    G4,
    BpE,
    BpH,
) -> tuple[jax.Array, jax.Array, jax.Array]:
    """``(u, pi, v)`` at the current sample from e_y (..., p), F_hat (..., m), pi(t - tau) (...,) and
    v(t - tau) (..., m)."""
    Ke = matvec(K, e_y)
    pi = G1 * pi_past + G2 * jnp.sum(Ke * Ke, axis=-1)  # (31)
    v = G3 * v_past + G4 * Ke  # (32)
    u = pi[..., None] * Ke - matvec(BpE, v) - matvec(BpH, F_hat)  # (30)
    return u, pi, v
