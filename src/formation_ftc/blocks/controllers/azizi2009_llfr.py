"""Relative-output formation law on a chain and low-level fault recovery (LLFR) allocation with
mode-dependent weights (Azizi & Khorasani 2009, Sec. II, eq. (3)).

Per axis, the relative output of the chain pair (i, i+1) obeys ``e_ij'' = b_j u_j - b_i u_i + ...``; the
formation law asks for the relative acceleration::

    p_ij = xdd_ij^d - lambda1 e'_ij - lambda0 e_ij                               # Sec. II

and the allocation distributes it over the satellites with the weighted least-effort solution of
eq. (3), ``u = J_aug(alpha, b_hat)^-1 [p; 0] = M(alpha, b_hat) p``
(:func:`formation_ftc.design.allocation.allocation_matrix`). The HL supervisor's mode selects
(alpha, b_hat): Nominal (alpha, b_nominal), LLFR (alpha, b_hat), FLFR (alpha with alpha_k raised to
the FLFR weight, b_hat). The three matrices per axis are computed once per run.

Units: e [m], e' [m/s], p and xdd^d [m/s^2], u [m/s^2 per unit actuator gain].
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from formation_ftc.design.allocation import allocation_matrix

__all__ = ["relative_output_law", "mode_allocation_matrices", "allocate"]


def relative_output_law(e, e_dot, xdd_desired, lambda0, lambda1) -> jax.Array:
    """p_ij = xdd_ij^d - lambda1 e'_ij - lambda0 e_ij [m/s^2] (Sec. II), shapes (N-1, axes)."""
    return xdd_desired - lambda1 * e_dot - lambda0 * e


def mode_allocation_matrices(alpha, alpha_flfr, k: int, b_nominal, b_hat) -> jax.Array:
    """Allocation matrices of the modes Nominal, LLFR, FLFR: shape (3, axes, N, N-1) (eq. (3)).

    ``alpha`` (N,) weights; ``alpha_flfr`` the FLFR weight of satellite ``k`` (0-based); ``b_nominal``,
    ``b_hat`` (N, axes) nominal and estimated actuator gains [-].
    """
    alpha = jnp.asarray(alpha)
    alpha_f = alpha.at[k].set(alpha_flfr)
    alphas = jnp.stack([alpha, alpha, alpha_f])
    b_hats = jnp.stack(
        [jnp.asarray(b_nominal), jnp.asarray(b_hat), jnp.asarray(b_hat)]
    )  # (3, N, axes)
    return jax.vmap(lambda a, bh: jax.vmap(lambda bcol: allocation_matrix(a, bcol), in_axes=1)(bh))(
        alphas, b_hats
    )


def allocate(M, p) -> jax.Array:
    """u = M p per axis (eq. (3)): ``M`` (axes, N, N-1), ``p`` (N-1, axes) -> u (N, axes)."""
    return jnp.einsum("anm,ma->na", M, p)
