"""Distributed adaptive fault-tolerant formation control of Li et al. 2020 (Theorems 1 and 2).

Pure ``jax.numpy`` kernels; spacecraft are axis 0 (shapes (N, 3) for vectors, (N,) for scalars).

Composite error (eq. (6)): ``s_i = e_i2 + k_i e_i1``. With the regressor Y_i (eq. (8)) and the
consensus term ``sum_j c_ij (s_i - s_j)`` (Thm 1, eq. (24)) or ``sum_j c_ij (s_i - s_j(t - T_ij(t)))``
(Thm 2, eq. (42)) -- formed from what a graph network delivers
(:mod:`formation_ftc.components.networks.weighted_graph`) -- the control and the adaptive laws are
(vector form of E000-05)::

    xi_i  = m_hat_i Y_i + lambda_i s_i + consensus_i + sgn * d_hat_i tanh(s_i / sigma_i)   # (24)/(42)
    w_i   = xi_i^T s_i
    f_i   = -beta_hat_i^2 xi_i w_i / sqrt(beta_hat_i^2 w_i^2 + sigma_i^2)                  # (23)/(41)
    beta_hat_dot_i = gamma_i xi_i^T s_i                                                  # (25)/(43)
    m_hat_dot_i    = eta_i s_i^T Y_i                                                     # (26)/(44)
    d_hat_dot_i    = -mu_i upsilon_i sigma_i d_hat_i + mu_i ||s_i||_1                    # (27)/(45)

``sgn = +1`` is the corrected sign of the d_hat tanh term in both theorems (E000-04); eq. (42) as
printed has ``-1`` (pass ``d_sign=-1`` to reproduce the literal form).

Smoothing function sigma_i(t) > 0 with finite integral (eq. (11)): eq. (13) ``exp(-a t)`` or eq. (14)
``1/(a t^2)``; the latter is singular at t = 0, so it is used with a time offset t0 > 0 (the proof's
eq. (16) integrates from t0): ``1/(a (t + t0)^2)``.
"""

from __future__ import annotations

import jax.numpy as jnp

__all__ = [
    "sigma_exponential",
    "sigma_inverse_square",
    "li2020_control",
    "li2020_adaptation_rates",
]


def sigma_exponential(t, a):
    """sigma(t) = exp(-a t), eq. (13); a [1/s] > 0."""
    return jnp.exp(-a * t)


def sigma_inverse_square(t, a, t0):
    """sigma(t) = 1 / (a (t + t0)^2), eq. (14) shifted by t0 > 0 [s] (finite at t = 0); a [1/s^2]."""
    return 1.0 / (a * (t + t0) ** 2)


def li2020_control(s, Y, consensus, m_hat, beta_hat, d_hat, sigma, lam, d_sign=1.0):
    """Commanded force f_i [N] and xi_i of eqs. (23)-(24) / (41)-(42).

    Parameters
    ----------
    s : (N, 3) composite error [m/s]
    Y : (N, 3) regressor of eq. (8) [m/s^2]
    consensus : (N, 3) consensus term [m/s]
    m_hat, beta_hat, d_hat : (N,) mass [kg], 1/effectiveness [-] and disturbance-bound [N] estimates
    sigma : (N,) or scalar smoothing value sigma_i(t) [-]
    lam : (N,) or scalar gain lambda_i
    d_sign : +1 (E000-04, corrected) or -1 (literal eq. (42))

    Returns
    -------
    (f (N, 3) [N], xi (N, 3))
    """
    sigma = jnp.broadcast_to(jnp.asarray(sigma), m_hat.shape)
    lam = jnp.broadcast_to(jnp.asarray(lam), m_hat.shape)
    xi = (
        m_hat[:, None] * Y
        + lam[:, None] * s
        + consensus
        + d_sign * d_hat[:, None] * jnp.tanh(s / sigma[:, None])
    )  # eq. (24)/(42), E000-04
    w = jnp.sum(xi * s, axis=-1)  # xi^T s, E000-05
    b2 = beta_hat**2
    f = -(b2 * w / jnp.sqrt(b2 * w**2 + sigma**2))[:, None] * xi  # eq. (23)/(41), E000-05
    return f, xi


def li2020_adaptation_rates(s, Y, xi, d_hat, sigma, gamma, eta, mu, upsilon):
    """(beta_hat_dot, m_hat_dot, d_hat_dot), each (N,): eqs. (25)-(27) / (43)-(45)."""
    sigma = jnp.broadcast_to(jnp.asarray(sigma), d_hat.shape)
    beta_dot = gamma * jnp.sum(xi * s, axis=-1)  # eq. (25)
    m_dot = eta * jnp.sum(s * Y, axis=-1)  # eq. (26)
    d_dot = -mu * upsilon * sigma * d_hat + mu * jnp.sum(jnp.abs(s), axis=-1)  # eq. (27)
    return beta_dot, m_dot, d_dot
