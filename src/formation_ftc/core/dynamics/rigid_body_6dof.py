"""Truth-level 6-DOF model of one spacecraft: inertial translation (Yang2013 eq. (1)) and quaternion
attitude with gravity-gradient torque (eq. (4)).

State ``s = [R, V, omega, q]`` (13,): position R [m] and velocity V [m/s] in the Earth-centred inertial
frame F0, body rate omega [rad/s] in the body frame and the attitude quaternion q (vector first).
Also the reference dynamics (6) of the main spacecraft (with d = iota = 0). The gravity-gradient
torque uses R in body axes, ``C(q)^T R``. Kinematics follow (4); (6) prints ``+omega x q``, a sign
slip (E001-03), which is not copied.
"""

from __future__ import annotations

import jax.numpy as jnp

from formation_ftc.core.dynamics.attitude_quaternion import attitude_rhs
from formation_ftc.core.dynamics.two_body import two_body_rhs
from formation_ftc.core.orbit import MU_EARTH
from formation_ftc.core.quaternion import dcm_body_from_reference

__all__ = ["spacecraft_6dof_rhs"]


def spacecraft_6dof_rhs(t, s, force, torque, mass, J, d=None, iota=None, mu: float = MU_EARTH):
    """Time derivative of ``[R, V, omega, q]`` under eqs. (1) and (4).

    force, d [N]; torque, iota [N m]; mass [kg]; J (3, 3) [kg m^2]; mu [m^3/s^2].
    """
    trans = two_body_rhs(t, s[0:6], force, d, mass, mu)  # Yang2013 eq. (1)
    R_body = dcm_body_from_reference(s[9:13]) @ s[0:3]
    att = attitude_rhs(t, s[6:13], J, torque, iota, R_body, mu)  # Yang2013 eq. (4)
    return jnp.concatenate([trans, att])
