"""SIR-FTC baseline (Li et al. 2020, Sec. IV-D, their ref. [21]) on the measured relative state."""

from __future__ import annotations

from typing import Any

from formation_ftc.blocks.controllers.sir_ftc import sir_epsilon, sir_ftc_control, sir_ftc_rate
from formation_ftc.components.controllers.desired_formation import RotatingFormation
from formation_ftc.components.controllers.li2020_adaptive import VELOCITY_ERROR, composite_error
from formation_ftc.sim.components import Controller, FlightInputs, Signal, component, static

__all__ = ["SirFtcController"]


@component
class SirFtcController(Controller):
    """f_i = -(k0 + b_hat_i Phi / (||s_i|| + eps)) s_i [N] with the adaptive gain b_hat_i [N]
    (:mod:`formation_ftc.blocks.controllers.sir_ftc`) on s_i = e_i2 + k_i e_i1 (eq. (6)) of the measured
    (N, 6) relative state; no communication. Continuous-time (b_hat integrated with the plant)."""

    count: int = static()
    formation: RotatingFormation
    k: Any  # (N,) [1/s]
    k0: Any  # [kg/s]
    phi: Any  # Phi [-]
    sigma1: Any  # [1/s]
    sigma2: Any  # [kg/m]
    mu_s: Any  # [m/s]
    b_hat0: Any  # (N,) [N]

    def initial_state(self):
        return {"b_hat": self.b_hat0}

    def exogenous(self, t):
        return self.formation.at(t)

    def desired_position_at(self, exogenous):
        return exogenous["rho_d"]

    def output(self, t, state, inputs: FlightInputs):
        s, _, e2 = composite_error(inputs.measurement, inputs.exogenous, self.k)
        eps = sir_epsilon(self.mu_s, self.phi)
        f = sir_ftc_control(s, state["b_hat"], self.k0, self.phi, eps)
        rate = sir_ftc_rate(s, state["b_hat"], self.phi, eps, self.sigma1, self.sigma2)
        return f, {"b_hat": rate}, {"velocity_error": e2, "b_hat": state["b_hat"]}

    def signals(self):
        return (
            VELOCITY_ERROR,
            Signal("b_hat", ("spacecraft",), "N", "adaptive gain b_hat_i"),
        )
