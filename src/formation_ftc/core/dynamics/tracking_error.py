"""Closed-loop tracking-error dynamics of a spacecraft relative to its desired state (Yang2013 (2), (5)).

Errors are *desired minus actual*, expressed in the body frame F_i of the spacecraft: position error
e_R [m], velocity error e_V [m/s], angular-velocity error e_omega [rad/s] and quaternion error
(e_q, e_q4) [-]. With the known drift terms Phi [m/s^2] and Upsilon [N m] (which exclude the control
and disturbance inputs, Yang2013 E001-02)::

    e_R' = e_V - omega x e_R                                   # Yang2013 eq. (2)
    e_V' = -omega x e_V + Phi - f / M - d / M                  # Yang2013 eq. (2)
    J e_omega' = Upsilon + tau + iota                          # Yang2013 eq. (5)
    e_q' = 1/2 (e_q4 e_omega - e_omega x e_q),  e_q4' = -1/2 e_omega^T e_q

with mass M [kg], control force f and disturbance force d [N], control torque tau and disturbance
torque iota [N m] and the body rate omega [rad/s] of F_i (the omega x terms preserve the norm; None
drops them). The attitude part is the rigid body of
:func:`formation_ftc.core.dynamics.attitude_quaternion.rigid_body_quaternion_rates` without gyroscopic
term (it belongs to Upsilon).
"""

from __future__ import annotations

import jax.numpy as jnp

__all__ = ["translational_error_rates"]


def translational_error_rates(e_R, e_V, Phi, force, disturbance, mass, omega_body=None):
    """``(e_R', e_V')`` of eq. (2), each (..., 3) [m/s, m/s^2].

    ``mass`` [kg] broadcasts against (..., 3) (e.g. shape (N, 1)); ``omega_body`` (..., 3) [rad/s] or
    None (no rotating-frame terms).
    """
    de_R = e_V  # Yang2013 eq. (2)
    de_V = Phi - force / mass - disturbance / mass
    if omega_body is not None:
        de_R = de_R - jnp.cross(omega_body, e_R)
        de_V = de_V - jnp.cross(omega_body, e_V)
    return de_R, de_V
