"""SIR-FTC baseline used for comparison in Li et al. 2020, Sec. IV-D (their ref. [21]).

Per spacecraft, on the same composite error s_i = e_i2 + k_i e_i1 (eq. (6))::

    f_i      = -(k0 + k_i(t)) s_i
    k_i(t)   = b_hat_i Phi / (||s_i|| + eps)
    b_hat_dot_i = -sigma1 b_hat_i + sigma2 ||s_i||^2 Phi / (||s_i|| + eps)
    eps      = mu_S / (1 + Phi)

Symbols renamed to avoid clashes (E000-16): the paper's mu -> ``mu_s``, k_i(t) -> ``k_adaptive``.
Paper values: k0 = 20, Phi = 1, sigma1 = 1, sigma2 = 10, mu_S = 1, b_hat(0) = 10.
"""

from __future__ import annotations

import jax.numpy as jnp

__all__ = ["sir_epsilon", "sir_ftc_control", "sir_ftc_rate"]


def sir_epsilon(mu_s, phi):
    """eps = mu_S / (1 + Phi) [m/s]."""
    return mu_s / (1.0 + phi)


def sir_ftc_control(s, b_hat, k0, phi, eps):
    """Commanded force f_i = -(k0 + b_hat_i Phi/(||s_i|| + eps)) s_i [N]; s (N, 3), b_hat (N,)."""
    ns = jnp.linalg.norm(s, axis=-1)
    k_adaptive = b_hat * phi / (ns + eps)
    return -(k0 + k_adaptive)[:, None] * s


def sir_ftc_rate(s, b_hat, phi, eps, sigma1, sigma2):
    """b_hat_dot_i = -sigma1 b_hat_i + sigma2 ||s_i||^2 Phi / (||s_i|| + eps)."""
    ns = jnp.linalg.norm(s, axis=-1)
    return -sigma1 * b_hat + sigma2 * ns**2 * phi / (ns + eps)
