"""Yang2013 individual laws as components: the translational law (12) (a force on any translational
plant) and the attitude law (13) (a torque on any quaternion rigid body). Equations in
:mod:`formation_ftc.blocks.controllers.yang2013_individual`; each reads only
:class:`~formation_ftc.sim.components.FlightInputs`."""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp

from formation_ftc.blocks.controllers.yang2013_individual import (
    attitude_control,
    translational_control,
)
from formation_ftc.components.controllers._desired_position import desired_motion
from formation_ftc.sim.components import Controller, FlightInputs, component, static

__all__ = ["Yang2013TranslationalController", "Yang2013AttitudeController"]


@component
class Yang2013TranslationalController(Controller):
    """Feedback-linearising formation law (12) on the measured (N, 6) relative state y = [p, v] [m, m/s]::

        e_R = p^d(t) - p,  e_V = v^d(t) - v                     (errors desired minus actual, (7))
        f_i = M_i (Phi_i + (K1 + 1) e_R + K2 e_V),  Phi_i = a_i^d(t)     # Yang2013 eq. (12)

    ``p^d(t)`` is an expression per axis (in t [s] and the 1-based spacecraft number i; default 0); v^d
    and a^d are its exact time derivatives. The feed-forward Phi_i is the desired acceleration: the
    plant's own drift is taken as cancelled (exact at the error level of Yang2013, where the desired
    trajectory is zero and y is the deviation from it). ``mass`` (N,) [kg], ``K1`` [1/s^2] (e_R gain
    K1 + 1), ``K2`` [1/s], positive (E001-01).
    """

    count: int = static()
    mass: Any = 1.0
    K1: Any = 0.005
    K2: Any = 0.01
    desired_position: tuple[str, str, str] = static(default=("0", "0", "0"))

    def exogenous(self, t):
        return desired_motion(self.desired_position, self.count, t)

    def desired_position_at(self, exogenous):
        return exogenous["p"]

    def output(self, t, state, inputs: FlightInputs):
        y, d = inputs.measurement, inputs.exogenous
        e_R = d["p"] - y[:, 0:3]
        e_V = d["v"] - y[:, 3:6]
        f = translational_control(
            e_R, e_V, d["a"], self.mass[:, None], self.K1, self.K2
        )  # eq. (12)
        return f, None, {}


@component
class Yang2013AttitudeController(Controller):
    """Attitude law (13) on the measured attitude error ``{"omega": (N, 3), "q": (N, 4)}`` (e_omega
    [rad/s], (e_q, e_q4) [-])::

        tau_i = -Upsilon_i - J (K3 e_w + e_q + e_w (K4 |e_q|^2 + K5 e_q4^2) / (2 (|e_w|^2 + kappa)))

    with the drift Upsilon_i taken as cancelled (zero). ``nominal_inertia`` J (3, 3) [kg m^2] (the
    law's model, stated on board); K3, K4, K5 [1/s] and kappa [rad^2/s^2] positive (E001-01).
    """

    quantity = "torque"

    count: int = static()
    nominal_inertia: Any = None
    K3: Any = 0.2
    K4: Any = 1.0
    K5: Any = 1.0
    kappa: Any = 1e-3

    def output(self, t, state, inputs: FlightInputs):
        w, q = inputs.measurement["omega"], inputs.measurement["q"]
        tau = attitude_control(
            w,
            q[:, 0:3],
            q[:, 3],
            jnp.zeros_like(w),
            self.nominal_inertia,
            self.K3,
            self.K4,
            self.K5,
            self.kappa,
        )  # Yang2013 eq. (13)
        return tau, None, {}
