"""Controller ``li2020-adaptive``: the distributed adaptive fault-tolerant formation law of Li et al.
2020, Theorem 1 (eqs. (23)-(27)) over a ``graph`` network and Theorem 2 (eqs. (41)-(45)) over a
``delayed-graph``, on the measured relative state.

Kernels: pure ``jax.numpy``; spacecraft are axis 0 (shapes (N, 3) for vectors, (N,) for scalars).

Composite error (eq. (6)): ``s_i = e_i2 + k_i e_i1``. With the regressor Y_i (eq. (8)) and the
consensus term ``sum_j c_ij (s_i - s_j)`` (Thm 1, eq. (24)) or ``sum_j c_ij (s_i - s_j(t - T_ij(t)))``
(Thm 2, eq. (42)) -- formed from what a graph network delivers
(:mod:`formation_ftc.components.networks.graph`) -- the control and the adaptive laws are
(vector form of E000-05)::

    xi_i  = m_hat_i Y_i + lambda_i s_i + consensus_i + sgn * d_hat_i tanh(s_i / sigma_i)   # (24)/(42)
    w_i   = xi_i^T s_i
    f_i   = -beta_hat_i^2 xi_i w_i / sqrt(beta_hat_i^2 w_i^2 + sigma_i^2)                  # (23)/(41)
    beta_hat_dot_i = gamma_i xi_i^T s_i                                                  # (25)/(43)
    m_hat_dot_i    = eta_i s_i^T Y_i                                                     # (26)/(44)
    d_hat_dot_i    = -mu_i upsilon_i sigma_i d_hat_i + mu_i ||s_i||_1                    # (27)/(45)

``sgn = +1`` is the corrected sign of the d_hat tanh term in both theorems (E000-04); eq. (42) as
printed has ``-1`` (pass ``d_sign=-1`` to reproduce the literal form).

Smoothing function sigma_i(t) > 0 with finite integral (eq. (11)): eq. (13) ``exp(-a t)`` or eq. (14)
``1/(a t^2)``; the latter is singular at t = 0, so it is used with a time offset t0 > 0 (the proof's
eq. (16) integrates from t0): ``1/(a (t + t0)^2)``.
"""

from __future__ import annotations

from typing import Annotated, Any, ClassVar, Literal

import jax.numpy as jnp
from pydantic import Field

from formation_ftc.components._flight_defaults import NOMINAL_MASS
from formation_ftc.components._registry import BuildContext, builder_input, per_spacecraft, register
from formation_ftc.components._sections import positive_values, section_floats
from formation_ftc.components.controllers._formation import FormationSection, RotatingFormation
from formation_ftc.config.base import StrictModel
from formation_ftc.core.constants import MU_EARTH
from formation_ftc.core.dynamics.relative_lvlh import natural_acceleration_from_rates
from formation_ftc.sim.components import Controller, FlightInputs, Signal, component, static
from formation_ftc.sim.contract import VEC, as_float

__all__ = [
    "Li2020AdaptiveController",
    "Li2020Section",
    "ADAPTIVE_PARAMETERS",
    "composite_error",
    "consensus",
    "sigma_exponential",
    "sigma_inverse_square",
    "li2020_control",
    "li2020_adaptation_rates",
]


def sigma_exponential(t, a):
    """The smoothing function of eq. (13), sigma(t) = exp(-a t).

    Parameters
    ----------
    t : float or array_like
        Time [s].
    a : float or array_like
        Decay rate a_i [1/s], > 0 (per spacecraft: shape (N,)).

    Returns
    -------
    jax.Array
        sigma(t) [-], the broadcast shape of ``t`` and ``a``.

    Examples
    --------
    >>> round(float(sigma_exponential(2.0, 0.5)), 12)  # exp(-1)
    0.367879441171
    """
    return jnp.exp(-a * t)


def sigma_inverse_square(t, a, t0):
    """The smoothing function of eq. (14) shifted by t0 > 0 (finite at t = 0),
    sigma(t) = 1 / (a (t + t0)^2).

    Parameters
    ----------
    t : float or array_like
        Time [s].
    a : float or array_like
        Coefficient a_i [1/s^2], > 0 (per spacecraft: shape (N,)).
    t0 : float
        Time offset [s], > 0.

    Returns
    -------
    jax.Array
        sigma(t) [-].

    Examples
    --------
    >>> float(sigma_inverse_square(1.0, 0.25, 1.0))  # 1 / (0.25 * 2^2)
    1.0
    """
    return 1.0 / (a * (t + t0) ** 2)


def li2020_control(s, Y, consensus, m_hat, beta_hat, d_hat, sigma, lam, d_sign=1.0):
    """Commanded force f_i [N] and xi_i of eqs. (23)-(24) / (41)-(42).

    Parameters
    ----------
    s : array_like, shape (N, 3)
        Composite error [m/s].
    Y : array_like, shape (N, 3)
        Regressor of eq. (8) [m/s^2].
    consensus : array_like, shape (N, 3)
        Consensus term [m/s].
    m_hat : array_like, shape (N,)
        Mass estimate [kg].
    beta_hat : array_like, shape (N,)
        Inverse-effectiveness estimate [-].
    d_hat : array_like, shape (N,)
        Disturbance-bound estimate [N].
    sigma : float or array_like, shape (N,)
        Smoothing value sigma_i(t) [-].
    lam : float or array_like, shape (N,)
        Gain lambda_i [kg/s].
    d_sign : float, optional
        +1 (E000-04, corrected) or -1 (literal eq. (42)).

    Returns
    -------
    f : jax.Array, shape (N, 3)
        Commanded force [N].
    xi : jax.Array, shape (N, 3)
        xi_i of eq. (24) / (42).

    Examples
    --------
    With zero regressor, consensus and d_hat, xi = lambda s and f = -beta^2 xi w / sqrt(beta^2 w^2 +
    sigma^2) with w = xi^T s:

    >>> import numpy as np
    >>> s = np.array([[1.0, 0.0, 0.0]])
    >>> f, xi = li2020_control(s, np.zeros((1, 3)), np.zeros((1, 3)), np.ones(1), np.ones(1),
    ...                        np.zeros(1), 1.0, 2.0)
    >>> float(np.asarray(xi)[0, 0]), round(float(np.asarray(f)[0, 0]), 12)  # -2 * 2 / sqrt(4 + 1)
    (2.0, -1.788854382)
    """
    sigma = jnp.broadcast_to(jnp.asarray(sigma), m_hat.shape)
    lam = jnp.broadcast_to(jnp.asarray(lam), m_hat.shape)
    xi = (
        m_hat[:, None] * Y
        + lam[:, None] * s
        + consensus
        + d_sign * d_hat[:, None] * jnp.tanh(s / sigma[:, None])
    )  # eq. (24)/(42), E000-04
    w = jnp.sum(xi * s, axis=-1)  # xi^T s, E000-05
    b2 = beta_hat**2
    f = -(b2 * w / jnp.sqrt(b2 * w**2 + sigma**2))[:, None] * xi  # eq. (23)/(41), E000-05
    return f, xi


def li2020_adaptation_rates(s, Y, xi, d_hat, sigma, gamma, eta, mu, upsilon):
    """Rates of the adaptive parameters, eqs. (25)-(27) / (43)-(45).

    Parameters
    ----------
    s : array_like, shape (N, 3)
        Composite error [m/s].
    Y : array_like, shape (N, 3)
        Regressor of eq. (8) [m/s^2].
    xi : array_like, shape (N, 3)
        xi_i of eq. (24) / (42).
    d_hat : array_like, shape (N,)
        Disturbance-bound estimate [N].
    sigma : float or array_like, shape (N,)
        Smoothing value sigma_i(t) [-].
    gamma, eta, mu, upsilon : float or array_like, shape (N,)
        Adaptation gains gamma_i, eta_i, mu_i and the leakage upsilon_i.

    Returns
    -------
    beta_dot : jax.Array, shape (N,)
        gamma_i xi_i^T s_i, eq. (25).
    m_dot : jax.Array, shape (N,)
        eta_i s_i^T Y_i, eq. (26).
    d_dot : jax.Array, shape (N,)
        -mu_i upsilon_i sigma_i d_hat_i + mu_i ||s_i||_1, eq. (27).

    Examples
    --------
    >>> import numpy as np
    >>> s, Y, xi = np.array([[1.0, -2.0, 0.0]]), np.array([[3.0, 1.0, 0.0]]), np.array([[2.0, 0.0, 0.0]])
    >>> [float(np.asarray(r)[0]) for r in li2020_adaptation_rates(s, Y, xi, np.ones(1), 1.0,
    ...                                                           0.5, 2.0, 1.0, 0.1)]
    [1.0, 2.0, 2.9]
    """
    sigma = jnp.broadcast_to(jnp.asarray(sigma), d_hat.shape)
    beta_dot = gamma * jnp.sum(xi * s, axis=-1)  # eq. (25)
    m_dot = eta * jnp.sum(s * Y, axis=-1)  # eq. (26)
    d_dot = -mu * upsilon * sigma * d_hat + mu * jnp.sum(jnp.abs(s), axis=-1)  # eq. (27)
    return beta_dot, m_dot, d_dot


#: the adaptive parameters of the law (recorded signals) -> their units
ADAPTIVE_PARAMETERS = {"m_hat": "kg", "beta_hat": "1", "d_hat": "N"}
#: what each adaptive parameter estimates (the recorded signals' long names)
_ESTIMATES = {
    "m_hat": "mass estimate m_hat_i",
    "beta_hat": "inverse-effectiveness estimate beta_hat_i",
    "d_hat": "disturbance-bound estimate d_hat_i",
}
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
    d_hat [N] are integrated with the plant. Without a network the consensus term is zero; a loop
    without a reference orbit is refused (:meth:`needs`; built by hand without one, the
    natural-acceleration term of Y_i is zero).

    Fields are the ``[controller]`` fields of the same name: ``mu`` is the d_hat adaptation gain mu_i,
    ``orbit_mu`` the gravitational parameter of the on-board model [m^3/s^2].
    """

    count: int = static()
    formation: RotatingFormation
    k: Any  # (N,) [1/s]
    lam: Any  # (N,) lambda_i [kg/s]
    gamma: Any  # (N,) beta_hat gain
    eta: Any  # (N,) m_hat gain
    mu: Any  # (N,) d_hat gain mu_i
    upsilon: Any  # (N,) d_hat leakage
    m_hat0: Any  # (N,) [kg]
    beta_hat0: Any  # (N,) [-]
    d_hat0: Any  # (N,) [N]
    sigma_a: Any  # (N,) a_i of sigma_i(t)
    sigma_t0: Any = 1.0  # t0 of the inverse-square sigma [s]
    d_sign: Any = 1.0  # +1 corrected (E000-04), -1 literal eq. (42)
    orbit_mu: Any = MU_EARTH  # gravitational parameter of the on-board model [m^3/s^2]
    #: "exponential" (eq. (13)) or "inverse_square" (eq. (14))
    sigma_form: str = static(default="exponential")
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
                y[:, :3], y[:, 3:], ref["r_c"], ref["theta_dot"], ref["theta_ddot"], self.orbit_mu
            )
        Y = acc_nat + self.k[:, None] * (y[:, 3:] - d["v_d"]) - d["a_d"]  # eq. (8)
        cons = consensus(inputs.received, s)  # eq. (24) / (42)
        m_hat, beta_hat, d_hat = state["m_hat"], state["beta_hat"], state["d_hat"]
        f, xi = li2020_control(
            s, Y, cons, m_hat, beta_hat, d_hat, d["sigma"], self.lam, self.d_sign
        )  # eqs. (23)-(24) / (41)-(42)
        beta_dot, m_dot, d_dot = li2020_adaptation_rates(
            s, Y, xi, d_hat, d["sigma"], self.gamma, self.eta, self.mu, self.upsilon
        )  # (25)-(27)
        outputs = {"velocity_error": e2, **{name: state[name] for name in ADAPTIVE_PARAMETERS}}
        return f, {"m_hat": m_dot, "beta_hat": beta_dot, "d_hat": d_dot}, outputs

    def signals(self):
        return (
            VELOCITY_ERROR,
            *(
                Signal(name, ("spacecraft",), unit, _ESTIMATES[name])
                for name, unit in ADAPTIVE_PARAMETERS.items()
            ),
        )

    def needs(self) -> dict[str, str]:
        return {"reference-orbit": "form the natural acceleration of its regressor Y_i (eq. (8))"}


#: a per-spacecraft gain or initial estimate: one number or N, each finite and > 0
_Positive = Annotated[float | list[float], positive_values()]


class Li2020Section(StrictModel):
    """Li2020 adaptive FTC: Thm 1 (eqs. (23)-(27)) over a ``graph`` network, Thm 2 (eqs. (41)-(45))
    over a ``delayed-graph``. Per-spacecraft fields take one number or N."""

    #: the law's adaptive parameters (recorded signals) and their units, reported by the
    #: ``li2020-formation-errors`` evaluation (final values and values at 0.9 T)
    adaptive_parameters: ClassVar[dict[str, str]] = ADAPTIVE_PARAMETERS
    formation: FormationSection
    k: _Positive = Field(
        0.2, description="k_i of s_i = e_i2 + k_i e_i1 (eq. (6)) [1/s], > 0 (Lemma 2)."
    )
    lam: float | list[float] = Field(
        20.0, description="lambda_i [kg/s] (Li2020: Thm 1 20, Thm 2 15)."
    )
    gamma: float | list[float] = Field(
        0.1,
        description="gamma_i, beta_hat adaptation gain [s/(kg m^2)] (not in the paper: our choice, "
        "E000-12).",
    )
    eta: float | list[float] = Field(
        1.0,
        description="eta_i, m_hat adaptation gain [kg s/m^2] (not in the paper: our choice, E000-12).",
    )
    mu: float | list[float] = Field(
        1.0,
        description="mu_i, d_hat adaptation gain [N s/m] (not in the paper: our choice, E000-12).",
    )
    upsilon: float | list[float] = Field(
        0.01,
        description="upsilon_i, d_hat leakage gain [1/(N s)] per unit sigma (not in the paper: our "
        "choice, E000-12).",
    )
    m_hat0: _Positive = Field(
        NOMINAL_MASS,
        description="m_hat_i(0), initial mass estimate [kg], > 0 (default 100 kg, a stated nominal "
        "value).",
    )
    beta_hat0: float | list[float] = Field(
        1.0, description="beta_hat_i(0), initial inverse-effectiveness estimate [-]."
    )
    d_hat0: _Positive = Field(
        0.001, description="d_hat_i(0), initial disturbance-bound estimate [N], > 0 (eq. (27))."
    )
    sigma_a: _Positive = Field(
        0.001, description="a_i of sigma_i(t) [1/s] (exponential) or [1/s^2] (inverse square), > 0."
    )
    sigma_form: Literal["exponential", "inverse_square"] = Field(
        "exponential",
        description="sigma_i(t): 'exponential' exp(-a t) (eq. (13)) or 'inverse_square' "
        "1/(a (t + t0)^2) (eq. (14), shifted by t0).",
    )
    sigma_t0: float = Field(1.0, gt=0, description="t0 of the inverse-square sigma [s].")
    orbit_mu: float = Field(
        MU_EARTH, gt=0, description="Gravitational parameter of the on-board model [m^3/s^2]."
    )
    dhat_sign_literal: bool = builder_input(
        False,
        description="Use the printed sign of the d_hat tanh term (+ in eq. (24), Thm 1; - in eq. (42), "
        "Thm 2, i.e. over a delayed network) instead of + in both (E000-04).",
    )


#: per-spacecraft fields of the section (one number or N)
_PER_SPACECRAFT: tuple[str, ...] = ("k", "lam", "gamma", "eta", "mu", "upsilon")
_PER_SPACECRAFT += ("m_hat0", "beta_hat0", "d_hat0", "sigma_a")


def _build(sec: Li2020Section, ctx: BuildContext) -> Li2020AdaptiveController:
    """The controller of a validated ``[controller] type = "li2020-adaptive"`` section."""
    n = ctx.count
    per = {
        name: as_float(per_spacecraft(getattr(sec, name), n, f"controller.{name}"))
        for name in _PER_SPACECRAFT
    }
    # the printed '-' of eq. (42) belongs to Thm 2, the law over delayed links (E000-04)
    delayed = getattr(ctx.section("network"), "delays", None) is not None
    return Li2020AdaptiveController(
        count=n,
        formation=sec.formation.component(n),
        **per,
        **section_floats(sec, "sigma_t0", "orbit_mu"),
        d_sign=as_float(-1.0 if sec.dhat_sign_literal and delayed else 1.0),
        sigma_form=sec.sigma_form,
    )


register(
    "controller",
    "li2020-adaptive",
    Li2020Section,
    _build,
    "Li2020 distributed adaptive FTC (Thm 1 with a graph network, Thm 2 with a delayed one)",
)
