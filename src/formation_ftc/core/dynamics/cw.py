"""Linear Clohessy-Wiltshire (Hill) relative dynamics about a circular orbit (Gui2022 (1)-(3)).

State q = [x, y, z, xdot, ydot, zdot] in the LVLH/Hill frame: x radial (outward), y along-track,
z orbit normal; positions in m, velocities in m/s, inputs as accelerations in m/s^2 (force per unit
mass), mean motion n in rad/s.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

__all__ = [
    "cw_matrices",
    "cw_rhs",
    "cw_state_transition",
    "cw_closed_form",
    "cw_matrices_jax",
    "cw_free_motion",
]


def cw_matrices(n: float) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of q_dot = A q + B u: A = [[0, I], [A1, A2]], A1 = diag(3n^2, 0, -n^2), B = [0; I]."""
    A = np.zeros((6, 6))
    A[:3, 3:] = np.eye(3)
    A[3, 0] = 3 * n**2
    A[5, 2] = -(n**2)
    A[3, 4] = 2 * n
    A[4, 3] = -2 * n
    B = np.vstack([np.zeros((3, 3)), np.eye(3)])
    return A, B


def cw_rhs(t, q, u, n):
    """q_dot for state q (..., 6) and acceleration input u (..., 3)."""
    x, _, z, xd, yd, zd = (q[..., k] for k in range(6))
    ax = 3 * n**2 * x + 2 * n * yd + u[..., 0]
    ay = -2 * n * xd + u[..., 1]
    az = -(n**2) * z + u[..., 2]
    return jnp.stack([xd, yd, zd, ax, ay, az], axis=-1)


def cw_state_transition(n: float, t: float) -> np.ndarray:
    """Closed-form 6x6 state-transition matrix Phi(t)."""
    c, s = np.cos(n * t), np.sin(n * t)
    return np.array(
        [
            [4 - 3 * c, 0, 0, s / n, 2 * (1 - c) / n, 0],
            [6 * (s - n * t), 1, 0, -2 * (1 - c) / n, (4 * s - 3 * n * t) / n, 0],
            [0, 0, c, 0, 0, s / n],
            [3 * n * s, 0, 0, c, 2 * s, 0],
            [-6 * n * (1 - c), 0, 0, -2 * s, 4 * c - 3, 0],
            [0, 0, -n * s, 0, 0, c],
        ]
    )


def cw_closed_form(n: float, q0, t) -> np.ndarray:
    """Free-drift CW state at times t (array) from q0: Phi(t) q0, shape (len(t), 6)."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    q0 = np.asarray(q0, dtype=float)
    return np.stack([cw_state_transition(n, tk) @ q0 for tk in t])


# ------------------------------------------------------------------------------------------------
# JAX versions (traceable, vmappable and differentiable in n)
# ------------------------------------------------------------------------------------------------
def cw_matrices_jax(n) -> tuple[jnp.ndarray, jnp.ndarray]:
    """(A, B) of :func:`cw_matrices` as JAX arrays built from the (possibly traced) mean motion n [rad/s]."""
    z = jnp.zeros((), dtype=jnp.float64)
    one = 1.0 + z
    n = n + z
    n2 = n * n
    rows = [
        [z, z, z, one, z, z],
        [z, z, z, z, one, z],
        [z, z, z, z, z, one],
        [3 * n2, z, z, z, 2 * n, z],
        [z, z, z, -2 * n, z, z],
        [z, z, -n2, z, z, z],
    ]
    A = jnp.stack([jnp.stack(r) for r in rows])
    B = jnp.concatenate([jnp.zeros((3, 3)), jnp.eye(3)])
    return A, B


def cw_free_motion(n, q0, t):
    """Free-drift CW state Phi(t) q0 at one time t [s] (closed form) in JAX.

    ``q0`` has shape (..., 6) [m, m/s]; returns the same shape. Same formula as
    :func:`cw_state_transition` written element by element (no 6x6 matrix per call).
    """
    nt = n * t
    c, s = jnp.cos(nt), jnp.sin(nt)
    x0, y0, z0, xd, yd, zd = (q0[..., i] for i in range(6))
    return jnp.stack(
        [
            (4 - 3 * c) * x0 + (s / n) * xd + (2 / n) * (1 - c) * yd,
            6 * (s - nt) * x0 + y0 - (2 / n) * (1 - c) * xd + ((4 * s - 3 * nt) / n) * yd,
            c * z0 + (s / n) * zd,
            3 * n * s * x0 + c * xd + 2 * s * yd,
            -6 * n * (1 - c) * x0 - 2 * s * xd + (4 * c - 3) * yd,
            -n * s * z0 + c * zd,
        ],
        axis=-1,
    )
