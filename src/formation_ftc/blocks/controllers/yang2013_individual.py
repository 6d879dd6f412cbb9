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
amplitude decays as ``exp(-K2 t / 2)`` when underdamped -- the gains of SPEC P1.4 (K2 = eta = 0.01)
realise exactly the paper's eta (see :func:`formation_ftc.design.dwell_time.gains_for_decay_rate`).

The velocity-channel controller fault of Sec. 4 replaces K2 by K2f (:func:`translational_control`
takes the gain as an argument, so a fault or a supervisor's reconfiguration just passes another gain).
Units: e_R [m], e_V [m/s], e_w [rad/s], e_q, e_q4 [-], M [kg], J [kg m^2], f [N], tau [N m].
"""

from __future__ import annotations

from dataclasses import dataclass

import jax.numpy as jnp

__all__ = [
    "Yang2013Gains",
    "split_error_state",
    "translational_control",
    "attitude_control",
    "feedback_input",
    "input_norm",
]


@dataclass(frozen=True)
class Yang2013Gains:
    """Gains of (12)-(13): K1..K5 > 0 (E001-01) and the smoothing constant kappa > 0 [-].

    K1 [1/s^2 offset, e_R gain is K1+1], K2 [1/s], K3 [1/s], K4, K5 [1/s], kappa [rad^2/s^2].
    """

    K1: float = 0.005
    K2: float = 0.01
    K3: float = 0.2
    K4: float = 1.0
    K5: float = 1.0
    kappa: float = 1e-3

    def __post_init__(self) -> None:
        for name in ("K1", "K2", "K3", "K4", "K5", "kappa"):
            v = getattr(self, name)
            if not v > 0:
                raise ValueError(f"controller.{name} must be > 0 (E001-01: positive gains), got {v}")


def split_error_state(x):
    """(..., 13) -> (e_R, e_V, e_w, e_q, e_q4) with shapes (..., 3) x 4 and (...,)."""
    x = jnp.asarray(x)
    return x[..., 0:3], x[..., 3:6], x[..., 6:9], x[..., 9:12], x[..., 12]


def translational_control(e_R, e_V, Phi, mass, K1, K2):
    """Control force f of eq. (12) [N]; ``Phi`` is the known drift of (2) [m/s^2] (E001-02)."""
    K1 = jnp.asarray(K1)[..., None] if jnp.ndim(K1) else K1
    K2 = jnp.asarray(K2)[..., None] if jnp.ndim(K2) else K2
    return mass * (Phi + (K1 + 1.0) * e_R + K2 * e_V)  # Yang2013 eq. (12)


def attitude_control(e_w, e_q, e_q4, Upsilon, J, K3, K4, K5, kappa):
    """Control torque tau of eq. (13) [N m]; ``Upsilon`` is the known drift of (5) [N m] (E001-02)."""
    e_q4 = jnp.asarray(e_q4)
    shaping = (K4 * jnp.sum(e_q * e_q, axis=-1) + K5 * e_q4**2) / (
        2.0 * (jnp.sum(e_w * e_w, axis=-1) + kappa)
    )
    inner = K3 * e_w + e_q + e_w * shaping[..., None]
    return -Upsilon - jnp.einsum("ij,...j->...i", jnp.asarray(J), inner)  # Yang2013 eq. (13)


def feedback_input(x, mass, J, gains: Yang2013Gains, K2=None):
    """Feedback parts ``(f_fb, tau_fb)`` of (12)-(13) (drift feed-forward omitted, SPEC P1.4 Fig. 5).

    ``K2`` overrides ``gains.K2`` (per spacecraft array or scalar), e.g. with the faulty K2f.
    """
    e_R, e_V, e_w, e_q, e_q4 = split_error_state(x)
    zero3 = jnp.zeros_like(e_R)
    K2 = gains.K2 if K2 is None else K2
    f = translational_control(e_R, e_V, zero3, mass, gains.K1, K2)
    tau = attitude_control(e_w, e_q, e_q4, zero3, J, gains.K3, gains.K4, gains.K5, gains.kappa)
    return f, tau


def input_norm(f, tau):
    """``|u_i| = |[f; tau]|`` of (7) (mixed N and N m, as in the paper's Fig. 5)."""
    return jnp.sqrt(jnp.sum(f * f, axis=-1) + jnp.sum(tau * tau, axis=-1))
