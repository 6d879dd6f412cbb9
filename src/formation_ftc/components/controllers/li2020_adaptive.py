"""Distributed adaptive fault-tolerant formation law of Li et al. 2020 (Theorems 1 and 2)."""

from __future__ import annotations

from typing import Any, ClassVar

import jax.numpy as jnp

from formation_ftc.blocks.controllers.li2020_adaptive import (
    li2020_adaptation_rates,
    li2020_control,
    sigma_exponential,
    sigma_inverse_square,
)
from formation_ftc.components.controllers.desired_formation import RotatingFormation
from formation_ftc.core.dynamics.relative_lvlh import natural_acceleration_from_rates
from formation_ftc.core.orbit import MU_EARTH
from formation_ftc.sim.components import Controller, FlightInputs, Signal, component, static

__all__ = ["Li2020AdaptiveController", "composite_error", "consensus"]

VEC = ("spacecraft", "axis")
#: the recorded e_i2 of the laws on the composite error s_i = e_i2 + k_i e_i1 (eq. (6))
VELOCITY_ERROR = Signal(
    "velocity_error", VEC, "m s-1", "measured velocity minus desired velocity e_i2", "LVLH"
)


def composite_error(y, desired: dict, k):
    """(s, e1, e2) from the measured (N, 6) relative state ``y``: e_i1 = rho_i - rho_i^d [m],
    e_i2 = v_i - v_i^d [m/s], s_i = e_i2 + k_i e_i1 [m/s] (eq. (6)).

    Parameters
    ----------
    y : array_like, shape (N, 6)
        Measured relative state [m, m/s].
    desired : dict
        ``"rho_d"`` (N, 3) desired position [m] and ``"v_d"`` (N, 3) desired velocity [m/s].
    k : array_like, shape (N,)
        Gains k_i [1/s].

    Returns
    -------
    s : jax.Array, shape (N, 3)
        Composite error [m/s].
    e1 : jax.Array, shape (N, 3)
        Position error [m].
    e2 : jax.Array, shape (N, 3)
        Velocity error [m/s].

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.controllers.li2020_adaptive import composite_error
    >>> y = np.array([[1.0, 0.0, 0.0, 0.1, 0.0, 0.0]])
    >>> desired = {"rho_d": np.zeros((1, 3)), "v_d": np.zeros((1, 3))}
    >>> s, e1, e2 = composite_error(y, desired, np.array([0.5]))
    >>> np.asarray(s)
    array([[0.6, 0. , 0. ]])
    """
    e1 = y[:, :3] - desired["rho_d"]  # eq. (6)
    e2 = y[:, 3:] - desired["v_d"]
    return e2 + k[:, None] * e1, e1, e2


def consensus(received, s):
    """sum_j c_ij (s_i - s_j(t - T_ij)) from a graph network's delivery (eqs. (24) / (42)); zero
    without a network.

    Parameters
    ----------
    received : dict or None
        A graph network's delivery: ``"in_weight"`` (N,) sum_j c_ij [-] and ``"weighted_sum"`` (N, 3)
        sum_j c_ij s_j [m/s]; None without a network.
    s : array_like, shape (N, 3)
        Own composite errors s_i [m/s].

    Returns
    -------
    jax.Array, shape (N, 3)
        The consensus term [m/s].

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.controllers.li2020_adaptive import consensus
    >>> s = np.array([[1.0, 0.0, 0.0], [3.0, 0.0, 0.0]])
    >>> received = {"in_weight": np.array([1.0, 1.0]), "weighted_sum": s[::-1]}  # c_12 = c_21 = 1
    >>> np.asarray(consensus(received, s))[:, 0]
    array([-2.,  2.])
    >>> np.asarray(consensus(None, s))[:, 0]
    array([0., 0.])
    """
    if received is None:
        return jnp.zeros_like(s)
    return received["in_weight"][:, None] * s - received["weighted_sum"]


@component
class Li2020AdaptiveController(Controller):
    """Thm 1 (eqs. (23)-(27)) / Thm 2 (eqs. (41)-(45)) adaptive law on the measured relative state.

    Reads the measured (N, 6) relative state ``y``, the reference-orbit values (for the known part of
    the regressor Y_i, eq. (8)), the consensus delivered by a graph network (instantaneous: Thm 1;
    delayed: Thm 2) and its own time signals (desired formation, smoothing function sigma_i(t)).
    Transmits s_i (eq. (6)). Continuous-time: its adaptive states m_hat [kg], beta_hat [-] and
    d_hat [N] are integrated with the plant. Without a reference orbit the natural-acceleration term of
    Y_i is zero; without a network the consensus term is zero.
    """

    count: int = static()
    formation: RotatingFormation
    k: Any  # (N,) [1/s]
    lam: Any  # (N,) lambda_i [kg/s]
    gamma: Any  # (N,) beta_hat gain
    eta: Any  # (N,) m_hat gain
    adapt_mu: Any  # (N,) d_hat gain mu_i
    upsilon: Any  # (N,) d_hat leakage
    m_hat0: Any  # (N,) [kg]
    beta_hat0: Any  # (N,) [-]
    d_hat0: Any  # (N,) [N]
    sigma_a: Any  # (N,) a_i of sigma_i(t)
    sigma_t0: Any = 1.0  # t0 of the inverse-square sigma [s]
    d_sign: Any = 1.0  # +1 corrected (E000-04), -1 literal eq. (42)
    mu: Any = MU_EARTH  # gravitational parameter of the on-board model [m^3/s^2]
    sigma_form: str = static(
        default="exponential"
    )  # "exponential" (eq. (13)) or "inverse_square" (eq. (14))
    uses_messages: ClassVar[bool] = True

    def initial_state(self):
        return {"m_hat": self.m_hat0, "beta_hat": self.beta_hat0, "d_hat": self.d_hat0}

    def exogenous(self, t):
        d = self.formation.at(t)
        if self.sigma_form == "exponential":
            d["sigma"] = sigma_exponential(t, self.sigma_a)  # eq. (13)
        else:
            d["sigma"] = sigma_inverse_square(t, self.sigma_a, self.sigma_t0)  # eq. (14), shifted
        return d

    def desired_position_at(self, exogenous):
        return exogenous["rho_d"]

    def message(self, t, inputs: FlightInputs):
        return composite_error(inputs.measurement, inputs.exogenous, self.k)[0]

    def output(self, t, state, inputs: FlightInputs):
        y, d, ref = inputs.measurement, inputs.exogenous, inputs.reference
        s, _, e2 = composite_error(y, d, self.k)
        if ref is None:
            acc_nat = jnp.zeros_like(s)
        else:
            acc_nat = natural_acceleration_from_rates(
                y[:, :3], y[:, 3:], ref["r_c"], ref["theta_dot"], ref["theta_ddot"], self.mu
            )
        Y = acc_nat + self.k[:, None] * (y[:, 3:] - d["v_d"]) - d["a_d"]  # eq. (8)
        cons = consensus(inputs.received, s)  # eq. (24) / (42)
        f, xi = li2020_control(
            s,
            Y,
            cons,
            state["m_hat"],
            state["beta_hat"],
            state["d_hat"],
            d["sigma"],
            self.lam,
            self.d_sign,
        )  # eqs. (23)-(24) / (41)-(42)
        beta_dot, m_dot, d_dot = li2020_adaptation_rates(
            s, Y, xi, state["d_hat"], d["sigma"], self.gamma, self.eta, self.adapt_mu, self.upsilon
        )  # (25)-(27)
        outputs = {
            "velocity_error": e2,
            "m_hat": state["m_hat"],
            "beta_hat": state["beta_hat"],
            "d_hat": state["d_hat"],
        }
        return f, {"m_hat": m_dot, "beta_hat": beta_dot, "d_hat": d_dot}, outputs

    def signals(self):
        return (
            VELOCITY_ERROR,
            Signal("m_hat", ("spacecraft",), "kg", "mass estimate m_hat_i"),
            Signal("beta_hat", ("spacecraft",), "1", "inverse-effectiveness estimate beta_hat_i"),
            Signal("d_hat", ("spacecraft",), "N", "disturbance-bound estimate d_hat_i"),
        )
