"""Individual (per-spacecraft) controllers of Yang et al. 2013, eqs. (12)-(13).

Each spacecraft i tracks the main spacecraft 1 only (leader-following: its error state
``x_i = [e_R, e_V, e_omega, e_q, e_q4]`` in R^13 (7) is formed from its own measurements and the main
spacecraft's broadcast state). The controllers are feedback-linearising::

    f_i   = M_i (Phi_i + (K1 + 1) e_R + K2 e_V)                                          # eq. (12)
    tau_i = -Upsilon_i - J_i (K3 e_w + e_q + e_w (K4 |e_q|^2 + K5 e_q4^2) / (2(|e_w|^2 + kappa)))  # eq. (13)

where Phi_i, Upsilon_i are the *known drift* (feed-forward) terms of the error dynamics (2), (5) --
without f, d, tau, iota (E001-02). The gains must be **positive** (E001-01; the paper's "negative
constants" would destabilise the loop). With the drift cancelled, the translational closed loop is
``e_V_dot = -(K1+1) e_R - K2 e_V - d/M`` and ``e_R_dot = e_V`` (omega x terms norm-preserving), whose
amplitude decays as ``exp(-K2 t / 2)`` when underdamped -- gains with K2 = eta realise exactly the
paper's decay rate eta (see :func:`formation_ftc.design.dwell_time.gains_for_decay_rate`).

Units: e_R [m], e_V [m/s], e_w [rad/s], e_q, e_q4 [-], M [kg], J [kg m^2], f [N], tau [N m].
The components wrapping these laws are in :mod:`formation_ftc.components.controllers.yang2013_individual`.
"""

from __future__ import annotations

import jax.numpy as jnp

from formation_ftc.core.dynamics.two_body import gravity_acceleration
from formation_ftc.core.orbit import MU_EARTH

__all__ = [
    "translational_control",
    "attitude_control",
    "input_norm",
    "translational_drift",
]


def translational_control(e_R, e_V, Phi, mass, K1, K2):
    """Control force f of eq. (12) [N]; ``Phi`` is the known drift of (2) [m/s^2] (E001-02).

    ``K1`` [1/s^2 offset: the e_R gain is K1 + 1], ``K2`` [1/s] scalars or per-spacecraft arrays.
    """
    K1 = jnp.asarray(K1)[..., None] if jnp.ndim(K1) else K1
    K2 = jnp.asarray(K2)[..., None] if jnp.ndim(K2) else K2
    return mass * (Phi + (K1 + 1.0) * e_R + K2 * e_V)  # Yang2013 eq. (12)


def attitude_control(e_w, e_q, e_q4, Upsilon, J, K3, K4, K5, kappa):
    """Control torque tau of eq. (13) [N m]; ``Upsilon`` is the known drift of (5) [N m] (E001-02).

    K3 [1/s], K4, K5 [1/s], smoothing constant kappa [rad^2/s^2], J (3, 3) [kg m^2].
    """
    e_q4 = jnp.asarray(e_q4)
    shaping = (K4 * jnp.sum(e_q * e_q, axis=-1) + K5 * e_q4**2) / (
        2.0 * (jnp.sum(e_w * e_w, axis=-1) + kappa)
    )
    inner = K3 * e_w + e_q + e_w * shaping[..., None]
    return -Upsilon - jnp.einsum("ij,...j->...i", jnp.asarray(J), inner)  # Yang2013 eq. (13)


def input_norm(f, tau):
    """``|u_i| = |[f; tau]|`` of (7) (N and N m combined, as in the paper's Fig. 5)."""
    return jnp.sqrt(jnp.sum(f * f, axis=-1) + jnp.sum(tau * tau, axis=-1))


def translational_drift(R_i, R_main, a_main, a_desired, mu: float = MU_EARTH):
    """Known drift Phi_i of (2) for a follower whose frame F_i is parallel to F0 (omega_i = 0) [m/s^2].

    With e_R = R~^d - (R_i - R_1) and e_V = V~^d - (V_i - V_1),
    ``e_V_dot = a^d - g(R_i) + a_1 - f/M - d/M``, so ``Phi_i = a^d - g(R_i) + a_1`` where g is the
    inverse-square gravity and a_1 the main spacecraft's (measured) acceleration; it contains no f, d
    (E001-02). (12) then makes the error dynamics exactly the error-level closed loop of method
    ``yang2013``.
    """
    return a_desired - gravity_acceleration(R_i, mu) + a_main
