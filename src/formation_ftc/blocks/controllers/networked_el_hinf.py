"""Distributed H-infinity synchronisation / tracking control of networked EL systems with adaptive
fault recovery (Mehrabian, Tafazoli, Khorasani, eqs. (6), (8), (18)-(19), (25)-(26)).

Per agent j (k generalised coordinates; gains are per-channel diagonals, arrays (m, k))::

    q~_j = q_j - e_j,   e_j = q*(t) + q_j^b                         errors (Sec. III)
    r_j  = e_dot_j - K_P q~_j - K_I z_j,      z_j = int q~_j          reference velocity
    s_j  = q_dot_j - r_j = q~_dot_j + K_P q~_j + K_I z_j             (= [K_I, K_P, I] x_j)
    r_dot_j = e_ddot_j - K_P q~_dot_j - K_I q~_j
    u_j  = D^_j(q_j) r_dot_j + C^_j(q_j, q_dot_j) r_j + tau_j        (6), (25)   [E003-04: D r_dot]

with D^, C^ built from the nominal inertia, K_P = K-bar (proportional) and K_I = K-double-bar
(integral) as in E003-03. The synchronisation law (8) is garbled in print (E003-01); two readings:

* ``law="literal"`` (default; first line of (8))::

      tau_j = -1/2 (K_j - I/gamma_j^2) s_j + alpha_j/2 K_j avg_{n in N_j} s_n + Gamma_j

  consensus-mode gain 1/2[(1 - alpha) K - gamma^-2] > 0 only for alpha < 1 - 1/(K gamma^2).
* ``law="diffusive"`` [CHOICE, robust]::

      tau_j = -1/2 (K_j - I/gamma_j^2) s_j - alpha_j/2 K_j avg_{n in N_j} (s_j - s_n) + Gamma_j

Fault compensation on the channels the FDI flags (18)-(19), (26) [E003-06: (26) is a rate law]::

    Gamma_{p,j}    = -sat(s_{p,j} / phi_b) u^_{p,j}      ``compensation="sat"``  (Remark 1)
                   = -sgn(s_{p,j}) u^_{p,j}              ``compensation="sign"`` (as printed)
                   = -u^_{p,j}                           ``compensation="certainty_equivalence"`` (E003-07)
    u^_dot_{p,j}   = sigma_{p,j} s_{p,j} - e_{p,j} (u^_{p,j} - u*_{p,j}(t))

Unflagged channels have Gamma = 0 and a frozen estimate (u^ = 0 before the FDI activates).
Everything is pure jax.numpy over arrays (m, k); the neighbour average uses the row-normalised
adjacency ``avg = D_deg^-1 A`` (the 1/|N_j| of (8)).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, NamedTuple

import jax
import jax.numpy as jnp

from formation_ftc.core.dynamics.euler_lagrange import el_forces

__all__ = [
    "LAWS",
    "COMPENSATIONS",
    "ELHinfConfig",
    "ELHinfErrors",
    "ELHinfOutput",
    "tracking_errors",
    "synchronisation_torque",
    "compensation_torque",
    "adaptation_rate",
    "control",
    "modal_damping",
]

LAWS = ("literal", "diffusive")
COMPENSATIONS = ("sat", "sign", "certainty_equivalence")


@dataclass(frozen=True)
class ELHinfConfig:
    """Structure of the controller (static)."""

    law: Literal["literal", "diffusive"] = "literal"
    compensation: Literal["sat", "sign", "certainty_equivalence"] = "sat"

    def __post_init__(self) -> None:
        if self.law not in LAWS:
            raise ValueError(f"controller.law must be one of {LAWS}, got {self.law!r}")
        if self.compensation not in COMPENSATIONS:
            raise ValueError(
                f"controller.compensation must be one of {COMPENSATIONS}, got {self.compensation!r}"
            )


class ELHinfErrors(NamedTuple):
    q_tilde: jax.Array  # q - e [rad]
    r: jax.Array  # reference velocity [rad/s]
    r_dot: jax.Array  # its derivative [rad/s^2]
    s: jax.Array  # sliding variable q_dot - r [rad/s]


class ELHinfOutput(NamedTuple):
    u: jax.Array  # commanded generalised force (6) [N m]
    s: jax.Array  # sliding variable [rad/s]
    q_tilde: jax.Array  # tracking error [rad]
    tau_sync: jax.Array  # H-infinity synchronisation part of tau (8) [N m]
    gamma_comp: jax.Array  # fault compensation Gamma (18) [N m]


def tracking_errors(q, qdot, z, e, e_dot, e_ddot, K_P, K_I) -> ELHinfErrors:
    """Errors of Sec. III (all (m, k)); ``z`` is the integral of q~ [rad s]."""
    q_tilde = q - e
    q_tilde_dot = qdot - e_dot
    r = e_dot - K_P * q_tilde - K_I * z
    r_dot = e_ddot - K_P * q_tilde_dot - K_I * q_tilde
    return ELHinfErrors(q_tilde, r, r_dot, qdot - r)


def synchronisation_torque(s, avg, K, alpha, gamma, law: str = "literal"):
    """tau-bar + tau-tilde of (8) [N m]; s, K (m, k); alpha, gamma (m,); avg (m, m) row-normalised."""
    a = alpha[:, None]
    own = -0.5 * (K - 1.0 / gamma[:, None] ** 2) * s  # Mehrabian (8), tau-bar
    s_avg = avg @ s
    if law == "literal":
        return own + 0.5 * a * K * s_avg  # (8) first line, E003-01
    if law == "diffusive":
        return own - 0.5 * a * K * (
            avg.sum(axis=1, keepdims=True) * s - s_avg
        )  # E003-01 alternative
    raise ValueError(f"unknown law {law!r}; valid: {LAWS}")


def compensation_torque(s, u_hat, flag, phi_b, mode: str = "sat"):
    """Gamma of (18) on flagged channels [N m]; phi_b is the boundary-layer width [rad/s]."""
    if mode == "sat":
        g = jnp.clip(s / phi_b, -1.0, 1.0) * u_hat  # Remark 1
    elif mode == "sign":
        g = jnp.sign(s) * u_hat  # (18) as printed
    elif mode == "certainty_equivalence":
        g = u_hat  # E003-07 variant
    else:
        raise ValueError(f"unknown compensation {mode!r}; valid: {COMPENSATIONS}")
    return -flag * g


def adaptation_rate(s, u_hat, u_star, flag, sigma, e_gain):
    """u^_dot of (19)/(26) on flagged channels [N m / s]; zero elsewhere."""
    return flag * (sigma * s - e_gain * (u_hat - u_star))


def control(q, qdot, z, u_hat, flag, e, e_dot, e_ddot, J_hat, p, cfg: ELHinfConfig) -> ELHinfOutput:
    """Full law (6)+(8)+(18) for all agents. ``p`` holds K, K_P, K_I, sigma, e_gain (m, k), alpha,
    gamma (m,), phi_b (scalar), avg (m, m); J_hat (m, k, k) nominal inertia used by the model terms."""
    err = tracking_errors(q, qdot, z, e, e_dot, e_ddot, p["K_P"], p["K_I"])
    model = el_forces(q, qdot, err.r_dot, err.r, J_hat)  # (6): D^ r_dot + C^ r, g = 0
    tau_sync = synchronisation_torque(err.s, p["avg"], p["K"], p["alpha"], p["gamma"], cfg.law)
    gamma_comp = compensation_torque(err.s, u_hat, flag, p["phi_b"], cfg.compensation)
    u = model + tau_sync + gamma_comp
    return ELHinfOutput(u=u, s=err.s, q_tilde=err.q_tilde, tau_sync=tau_sync, gamma_comp=gamma_comp)


def modal_damping(K, alpha, gamma, mu, law: str = "literal"):
    """Damping of the s-dynamics ``D s_dot = tau`` (exact model, no fault) along an eigenvector of the
    row-normalised adjacency with eigenvalue ``mu`` in [-1, 1] (mu = 1: consensus direction) [N m s].

    literal: 1/2 (K - 1/gamma^2) - alpha K mu / 2      -> 1/2 [(1 - alpha) K - 1/gamma^2] at mu = 1
    diffusive: 1/2 (K - 1/gamma^2) + alpha K (1 - mu) / 2 -> 1/2 (K - 1/gamma^2) at mu = 1
    """
    base = 0.5 * (K - 1.0 / gamma**2)
    if law == "literal":
        return base - 0.5 * alpha * K * mu
    if law == "diffusive":
        return base + 0.5 * alpha * K * (1.0 - mu)
    raise ValueError(f"unknown law {law!r}; valid: {LAWS}")
