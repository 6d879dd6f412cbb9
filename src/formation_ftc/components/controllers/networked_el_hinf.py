"""Controller ``networked-el-hinf``: distributed H-infinity synchronisation / tracking control of
networked Euler-Lagrange attitudes with adaptive fault recovery (Mehrabian, Tafazoli, Khorasani, eqs.
(6), (8), (18)-(19), (25)-(26)).

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
A stated excitation (:func:`excitation`, ``excitation_amplitude`` > 0; default none) may be added to
the command, so that an identifying FDI can identify each channel's effectiveness on a settled hold.
Everything is pure jax.numpy over arrays (m, k); the neighbour average uses the row-normalised
adjacency ``avg = D_deg^-1 A`` (the 1/|N_j| of (8)).

The component. Measurement (flight side): the attitude of every spacecraft as a dict ``{"q": (m, 3) Euler angles
[theta, phi, psi] [rad], "w": (m, 3) body rates [rad/s]}`` (the state of
:class:`~formation_ftc.components.plants.euler_angle_attitude.EulerAngleAttitudePlant` through
perfect sensors; a quaternion plant needs a sensor that converts to this form). The command is the
generalised torque conjugate to the Euler angles [N m].

Neighbours: the law needs every neighbour's sliding variable s_n = q_dot_n - r_n *at the same instant*
(8). s_n contains the neighbour's integral state z_n, which a transmitted message cannot carry here
(a :class:`~formation_ftc.sim.components.Controller` message is a function of the flight inputs, not
of the controller state), and the paper assumes ideal, undelayed communication. So the law reads the
measurement of the whole formation and applies the graph through the row-normalised adjacency leaf
``avg`` (1/|N_j| of (8)): an ideal network. A delayed network is rejected at validation.

Fault recovery: the estimator's report (flag, u*), a
:class:`~formation_ftc.components.estimators.scripted_fdi.FDIOutput` or the same two fields of a
detected FDI, drives Gamma (18) and the adaptive estimate u^ (19); without an estimator both are zero
(no reconfiguration).

Capabilities: the law needs ``euler-angle-measurement`` (on a quaternion plant: the
``quaternion-euler`` sensors) and ``generalised-torque-actuation`` (on a quaternion plant: the
``euler-torque-allocation`` actuator, or ``fault-battery`` with ``euler_allocation``), and provides
``euler-angle-law``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from pydantic import Field, model_validator

from formation_ftc.components._flight_defaults import MEHRABIAN_NOMINAL_INERTIA
from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.components._sections import Inertia, Vec3Expr, expression_text, section_floats
from formation_ftc.components.expressions import vector_expression
from formation_ftc.config.base import StrictModel
from formation_ftc.core import graph as graphs
from formation_ftc.core.constants import check_away_from_singularity
from formation_ftc.core.dynamics.euler_lagrange import el_forces, euler_rates_from_body_rates
from formation_ftc.sim.components import Controller, FlightInputs, Signal, component, static
from formation_ftc.sim.contract import VEC, as_float

__all__ = [
    "NetworkedElHinfController",
    "NetworkedElHinfSection",
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
    "excitation",
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
    """Errors of Sec. III.

    Parameters
    ----------
    q, qdot : array_like, shape (m, k)
        Generalised coordinates [rad] and their rates [rad/s].
    z : array_like, shape (m, k)
        Integral of the tracking error q~ [rad s].
    e, e_dot, e_ddot : array_like, shape (m, k)
        Desired coordinates [rad] and their first two derivatives [rad/s, rad/s^2].
    K_P, K_I : array_like
        Proportional [1/s] and integral [1/s^2] gains, per channel.

    Returns
    -------
    ELHinfErrors
        q~ [rad], r [rad/s], r_dot [rad/s^2] and s = q_dot - r [rad/s].

    Examples
    --------
    At rest 0.1 rad from the desired attitude, s = K_P q~:

    >>> import numpy as np
    >>> z = np.zeros((1, 3))
    >>> err = tracking_errors(np.array([[0.1, 0.0, 0.0]]), z, z, z, z, z, 0.16, 0.001)
    >>> np.asarray(err.s).tolist()
    [[0.016, 0.0, 0.0]]
    """
    q_tilde = q - e
    q_tilde_dot = qdot - e_dot
    r = e_dot - K_P * q_tilde - K_I * z
    r_dot = e_ddot - K_P * q_tilde_dot - K_I * q_tilde
    return ELHinfErrors(q_tilde, r, r_dot, qdot - r)


def synchronisation_torque(s, avg, K, alpha, gamma, law: str = "literal"):
    """tau-bar + tau-tilde of (8) [N m].

    Parameters
    ----------
    s : array_like, shape (m, k)
        Sliding variables [rad/s].
    avg : array_like, shape (m, m)
        Row-normalised adjacency (the 1/|N_j| of (8)).
    K : array_like, shape (m, k)
        Gain K_j [N m s].
    alpha, gamma : array_like, shape (m,)
        Synchronisation weight and H-infinity level [-].
    law : {"literal", "diffusive"}
        Reading of (8) (E003-01).

    Returns
    -------
    jax.Array, shape (m, k)
        The synchronisation torque [N m].

    Examples
    --------
    Two spacecraft, gamma = 1 (no own term for K = 1): the literal law pulls towards the neighbour's
    s, the diffusive one towards the difference.

    >>> import numpy as np
    >>> s, avg, K = np.array([[1.0, 0, 0], [0, 0, 0]]), np.array([[0.0, 1], [1, 0]]), np.ones((2, 3))
    >>> np.asarray(synchronisation_torque(s, avg, K, np.full(2, 0.5), np.ones(2)))[:, 0].tolist()
    [0.0, 0.25]
    >>> t = synchronisation_torque(s, avg, K, np.full(2, 0.5), np.ones(2), "diffusive")
    >>> np.asarray(t)[:, 0].tolist()
    [-0.25, 0.25]
    """
    a = alpha[:, None]
    own = -0.5 * (K - 1.0 / gamma[:, None] ** 2) * s  # Mehrabian (8), tau-bar
    s_avg = avg @ s
    if law == "literal":
        return own + 0.5 * a * K * s_avg  # (8) first line, E003-01
    if law == "diffusive":
        # E003-01 alternative
        return own - 0.5 * a * K * (avg.sum(axis=1, keepdims=True) * s - s_avg)
    raise ValueError(f"unknown law {law!r}; valid: {LAWS}")


def compensation_torque(s, u_hat, flag, phi_b, mode: str = "sat"):
    """Gamma of (18) on the flagged channels [N m].

    Parameters
    ----------
    s : array_like, shape (m, k)
        Sliding variables [rad/s].
    u_hat : array_like, shape (m, k)
        Adaptive fault estimates [N m].
    flag : array_like, shape (m, k)
        1 on the channels the FDI flags [-].
    phi_b : float
        Boundary-layer width of sat(s / phi_b) [rad/s].
    mode : {"sat", "sign", "certainty_equivalence"}
        The compensation (Remark 1, (18) as printed, E003-07).

    Returns
    -------
    jax.Array, shape (m, k)
        Gamma [N m] (0 on unflagged channels).

    Examples
    --------
    >>> import numpy as np
    >>> g = compensation_torque(np.array([[0.005, -1.0, 1.0]]), np.full((1, 3), 2.0),
    ...                         np.array([[1.0, 1.0, 0.0]]), 0.01)
    >>> (np.asarray(g) + 0.0).tolist()
    [[-1.0, 2.0, 0.0]]
    """
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
    """u^_dot of (19)/(26) on the flagged channels [N m / s]; zero elsewhere.

    Parameters
    ----------
    s : array_like, shape (m, k)
        Sliding variables [rad/s].
    u_hat, u_star : array_like, shape (m, k)
        Adaptive estimate and the FDI's estimate u* [N m].
    flag : array_like, shape (m, k)
        1 on the channels the FDI flags [-].
    sigma : array_like
        Adaptation gain [N m / rad].
    e_gain : array_like
        Pull towards the FDI's estimate [1/s].

    Returns
    -------
    array_like, shape (m, k)
        The rate of u^ [N m / s].

    Examples
    --------
    >>> import numpy as np
    >>> one = np.array([[1.0, 1.0]])
    >>> adaptation_rate(0.1 * one, one, 1.5 * one, np.array([[1.0, 0.0]]), 0.5, 1.0).tolist()
    [[0.55, 0.0]]
    """
    return flag * (sigma * s - e_gain * (u_hat - u_star))


def control(q, qdot, z, u_hat, flag, e, e_dot, e_ddot, J_hat, p, cfg: ELHinfConfig) -> ELHinfOutput:
    """The full law (6) + (8) + (18) for all agents.

    Parameters
    ----------
    q, qdot, z : array_like, shape (m, k)
        Coordinates [rad], rates [rad/s] and the integral of the tracking error [rad s].
    u_hat, flag : array_like, shape (m, k)
        Adaptive fault estimate [N m] and the FDI's flag [-].
    e, e_dot, e_ddot : array_like, shape (m, k)
        Desired coordinates and their derivatives [rad, rad/s, rad/s^2].
    J_hat : array_like, shape (m, k, k)
        Nominal inertia of the model terms [kg m^2].
    p : dict
        ``K``, ``K_P``, ``K_I`` (m, k); ``alpha``, ``gamma`` (m,); ``phi_b`` (); ``avg`` (m, m).
    cfg : ELHinfConfig
        The reading of (8) and the compensation.

    Returns
    -------
    ELHinfOutput
        The command u [N m] and its parts.

    Examples
    --------
    At the desired attitude, at rest, no fault: no command.

    >>> import numpy as np
    >>> z = np.zeros((1, 3))
    >>> p = dict(K=np.full((1, 3), 20.0), K_P=np.full((1, 3), 0.16), K_I=np.full((1, 3), 0.001),
    ...          alpha=np.full(1, 0.86), gamma=np.full(1, 0.6), phi_b=0.01, avg=np.zeros((1, 1)))
    >>> J = np.diag([20.0, 18.0, 15.0])[None]
    >>> np.asarray(control(z, z, z, z, z, z, z, z, J, p, ELHinfConfig()).u).tolist()
    [[0.0, 0.0, 0.0]]
    """
    err = tracking_errors(q, qdot, z, e, e_dot, e_ddot, p["K_P"], p["K_I"])
    model = el_forces(q, qdot, err.r_dot, err.r, J_hat)  # (6): D^ r_dot + C^ r, g = 0
    tau_sync = synchronisation_torque(err.s, p["avg"], p["K"], p["alpha"], p["gamma"], cfg.law)
    gamma_comp = compensation_torque(err.s, u_hat, flag, p["phi_b"], cfg.compensation)
    u = model + tau_sync + gamma_comp
    return ELHinfOutput(u=u, s=err.s, q_tilde=err.q_tilde, tau_sync=tau_sync, gamma_comp=gamma_comp)


def excitation(t, amplitude, period):
    """A stated persistent excitation of the three generalised channels [N m]::

        d_p(t) = amplitude sin(2 pi t / period + 2 pi p / 3),     p = 0, 1, 2

    (phases a third of a period apart: the channels are excited at every instant, never all at their
    peak). It makes a loss of effectiveness on a settled hold, whose torque is almost zero, observable
    to an identifying FDI.

    Parameters
    ----------
    t : float
        Time [s].
    amplitude : float
        Amplitude [N m].
    period : float
        Period [s].

    Returns
    -------
    jax.Array, shape (3,)
        The torque added to every spacecraft's command [N m].

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.controllers.networked_el_hinf import excitation
    >>> np.round(np.asarray(excitation(0.0, 0.01, 10.0)), 5).tolist()
    [0.0, 0.00866, -0.00866]
    """
    phase = 2.0 * jnp.pi * (t / period + jnp.arange(3) / 3.0)
    return amplitude * jnp.sin(phase)


def modal_damping(K, alpha, gamma, mu, law: str = "literal"):
    """Damping of the s-dynamics ``D s_dot = tau`` (exact model, no fault) along an eigenvector of the
    row-normalised adjacency with eigenvalue ``mu`` in [-1, 1] (mu = 1: consensus direction) [N m s].

    literal: 1/2 (K - 1/gamma^2) - alpha K mu / 2      -> 1/2 [(1 - alpha) K - 1/gamma^2] at mu = 1
    diffusive: 1/2 (K - 1/gamma^2) + alpha K (1 - mu) / 2 -> 1/2 (K - 1/gamma^2) at mu = 1

    Parameters
    ----------
    K : float
        Gain [N m s].
    alpha, gamma : float
        Synchronisation weight and H-infinity level [-].
    mu : float
        Eigenvalue of the row-normalised adjacency [-].
    law : {"literal", "diffusive"}
        Reading of (8).

    Returns
    -------
    float
        The modal damping [N m s].

    Examples
    --------
    The Mehrabian gains: the literal law barely damps the consensus mode.

    >>> round(float(modal_damping(20.0, 0.86, 0.6, 1.0)), 6)
    0.011111
    >>> round(float(modal_damping(20.0, 0.86, 0.6, 1.0, "diffusive")), 6)
    8.611111
    """
    base = 0.5 * (K - 1.0 / gamma**2)
    if law == "literal":
        return base - 0.5 * alpha * K * mu
    if law == "diffusive":
        return base + 0.5 * alpha * K * (1.0 - mu)
    raise ValueError(f"unknown law {law!r}; valid: {LAWS}")


@component
class NetworkedElHinfController(Controller):
    """Law (6)+(8)+(18) with the adaptation (19), continuous (evaluated at every RK stage).

    Leaves (per spacecraft and channel unless stated): ``K`` [N m s], ``K_P`` [1/s], ``K_I`` [1/s^2],
    ``sigma``, ``e_gain`` [1/s] (m, 3); ``alpha``, ``gamma`` (m,) [-]; ``boundary_layer`` phi_b
    [rad/s]; ``avg`` (m, m) row-normalised adjacency; ``nominal_inertia`` (m, 3, 3) J^ [kg m^2].
    Static: ``law``, ``compensation`` (see :class:`ELHinfConfig`),
    the desired attitude ``e(t)`` per channel (expressions in t [s], i; derivatives by autodiff) and the
    undirected links ``links`` (0-based pairs) whose synchronisation errors are recorded.
    State: ``z`` = integral of the tracking error [rad s], ``u_hat`` (19) [N m].
    """

    quantity = "torque"
    #: the seed study's batch (60 runs x 8 spacecraft): 15 -> 10.6-11 us per run-step (sim.runtime.xla)
    batch_fast_compile = True

    count: int = static()
    K: Any = None
    K_P: Any = None
    K_I: Any = None
    sigma: Any = None
    e_gain: Any = None
    alpha: Any = None
    gamma: Any = None
    boundary_layer: Any = None
    avg: Any = None
    nominal_inertia: Any = None
    law: Literal["literal", "diffusive"] = static(default="literal")
    compensation: Literal["sat", "sign", "certainty_equivalence"] = static(default="sat")
    desired_attitude: tuple[str, str, str] = static(default=("0", "0", "0"))
    links: tuple[tuple[int, int], ...] = static(default=())
    excited: bool = static(default=False)  # a stated excitation is added to the command
    excitation_amplitude: Any = 0.0  # [N m] per generalised channel
    excitation_period: Any = 10.0  # [s]

    def __post_init__(self) -> None:
        ELHinfConfig(self.law, self.compensation)  # validates the static choices

    def initial_state(self):
        z = jnp.zeros((self.count, 3))
        return {"z": z, "u_hat": z}

    def exogenous(self, t):
        def e(tt):
            return vector_expression(self.desired_attitude, "desired.attitude", tt, self.count)

        e_d = jax.jacfwd(e)
        return {"e": e(t), "e_dot": e_d(t), "e_ddot": jax.jacfwd(e_d)(t)}

    def output(self, t, state, inputs: FlightInputs):
        y, d = inputs.measurement, inputs.exogenous
        q = y["q"]
        qdot = euler_rates_from_body_rates(q, y["w"])
        if inputs.estimate is None:
            flag = u_star = jnp.zeros((self.count, 3))
        else:
            flag, u_star = inputs.estimate.flag, inputs.estimate.estimate
        p = {k: getattr(self, k) for k in ("K", "K_P", "K_I", "alpha", "gamma", "avg")}
        p["phi_b"] = self.boundary_layer
        J, cfg = self.nominal_inertia, ELHinfConfig(self.law, self.compensation)
        ctl = control(
            q, qdot, state["z"], state["u_hat"], flag, d["e"], d["e_dot"], d["e_ddot"], J, p, cfg
        )  # (6) + (8) + (18)
        # (19)
        u_hat_dot = adaptation_rate(ctl.s, state["u_hat"], u_star, flag, self.sigma, self.e_gain)
        qt = ctl.q_tilde
        outputs = {
            "sliding_variable": ctl.s,
            "fault_estimate_adaptive": state["u_hat"],
            "tracking_error": qt,
        }
        u = ctl.u
        if self.excited:  # the stated test signal: part of the command every model on board knows
            u = u + excitation(t, self.excitation_amplitude, self.excitation_period)
        if self.links:
            j, n = jnp.asarray(self.links).T
            outputs["synchronisation_error"] = qt[j] - qt[n]
        return u, {"z": qt, "u_hat": u_hat_dot}, outputs

    def signals(self):
        sig = (
            Signal("sliding_variable", VEC, "rad s-1", "sliding variable s = q_dot - r"),
            Signal("fault_estimate_adaptive", VEC, "N m", "adaptive fault estimate u^ of (19)"),
            Signal("tracking_error", VEC, "rad", "tracking error q - e (measured)"),
        )
        if self.links:
            per_link = "tracking-error difference q~_j - q~_n over each undirected link"
            sig += (Signal("synchronisation_error", ("link", "axis"), "rad", per_link),)
        return sig

    def coords(self):
        return {"link": [f"{a + 1}-{b + 1}" for a, b in self.links]} if self.links else {}

    def needs(self) -> dict[str, str]:
        return {
            "euler-angle-measurement": "read the attitudes it synchronises",
            "generalised-torque-actuation": "apply its generalised torque",
        }

    def provides(self) -> frozenset[str]:
        return frozenset({"euler-angle-law"})


class NetworkedElHinfSection(StrictModel):
    """Distributed H-infinity synchronisation / tracking law with adaptive fault recovery (Euler angles)."""

    edges: list[tuple[int, int]] = builder_input(
        description="Undirected links as 1-based spacecraft pairs, unit weights [-]; "
        "the graph must be connected."
    )
    law: Literal["literal", "diffusive"] = Field(
        "literal", description="Reading of the synchronisation law."
    )
    compensation: Literal["sat", "sign", "certainty_equivalence"] = Field(
        "sat", description="Fault compensation Gamma: sat(s/phi_b) u^, sgn(s) u^ or -u^."
    )
    gamma: float = Field(0.6, gt=0.0, description="H-infinity level gamma_j [-].")
    alpha: float = Field(0.86, description="Synchronisation weight alpha_j [-].")
    K: float = Field(20.0, description="K_j = K I_3 [N m s].")
    K_P: float = Field(0.16, description="Proportional gain K_P I_3 [1/s].")
    K_I: float = Field(0.001, description="Integral gain K_I I_3 [1/s^2].")
    sigma: float = Field(0.5, gt=0.0, description="Adaptation gain sigma I_3 [N m / rad].")
    e_gain: float = Field(1.0, gt=0.0, description="Estimate pull towards the FDI estimate [1/s].")
    boundary_layer: float = Field(0.01, gt=0.0, description="Width phi_b of sat(s/phi_b) [rad/s].")
    nominal_inertia: Inertia = Field(
        MEHRABIAN_NOMINAL_INERTIA,
        description="Principal inertia of the law's model, known on board [kg m^2] (default 20, 18, "
        "15 kg m^2, Mehrabian's nominal J^, a stated value: never the plant's true inertia).",
    )
    desired_attitude: Vec3Expr = Field(
        ("0", "0", "0"),
        description="Desired [theta, phi, psi] per spacecraft, expressions in t [s], i [rad].",
    )
    excitation_amplitude: float = Field(
        0.0,
        ge=0.0,
        description="Amplitude of a stated sinusoidal excitation added to every generalised channel "
        "[N m] (phases a third of a period apart; 0: none). It lets an identifying FDI see a loss "
        "of effectiveness on a settled hold.",
    )
    excitation_period: float = Field(10.0, gt=0.0, description="Period of the excitation [s].")

    @model_validator(mode="after")
    def _check(self):
        if not self.edges:
            raise ValueError("edges: at least one link is needed")
        for k, (a, b) in enumerate(self.edges):
            if a < 1 or b < 1 or a == b:
                raise ValueError(
                    f"edges[{k}] = [{a}, {b}]: 1-based spacecraft numbers, no self-loops"
                )
        return self


def _build(sec: NetworkedElHinfSection, ctx: BuildContext) -> NetworkedElHinfController:
    """The controller of a validated ``[controller] type = "networked-el-hinf"`` section."""
    m = ctx.count
    for k, (a, b) in enumerate(sec.edges):
        if a > m or b > m:
            raise ValueError(f"controller.edges[{k}] = [{a}, {b}]: the plant has {m} spacecraft")
    A = graphs.adjacency(m, [(a - 1, b - 1) for a, b in sec.edges], directed=False)
    if not graphs.is_connected_undirected(A):
        raise ValueError(
            "controller.edges: the communication graph is not connected; the synchronisation law "
            "needs a connected undirected graph"
        )
    # the law's model is singular at pitch +-90 deg: a plant that states its initial 3-2-1 angles
    # (the quaternion plants) must start well away from it
    euler_angles = getattr(ctx.section("plant"), "euler_angles", None)
    if callable(euler_angles):
        check_away_from_singularity(
            euler_angles(), field="plant initial attitude (3-2-1 Euler angles)"
        )
    J = sec.nominal_inertia  # stated on board, never the plant's inertia
    ones = np.ones((m, 3))
    pj, pn = np.nonzero(np.triu(A > 0, 1))
    return NetworkedElHinfController(
        count=m,
        # gains per spacecraft and channel (N, 3), weights per spacecraft (N,)
        **{k: as_float(getattr(sec, k) * ones) for k in ("K", "K_P", "K_I", "sigma", "e_gain")},
        **{k: as_float(getattr(sec, k) * np.ones(m)) for k in ("alpha", "gamma")},
        **section_floats(sec, "boundary_layer", "excitation_amplitude", "excitation_period"),
        avg=as_float(graphs.row_normalized(A)),
        nominal_inertia=as_float(np.stack([np.diag(J)] * m)),
        law=sec.law,
        compensation=sec.compensation,
        desired_attitude=expression_text(sec.desired_attitude),
        links=tuple((int(a), int(b)) for a, b in zip(pj, pn, strict=True)),
        excited=sec.excitation_amplitude > 0,
    )


register(
    "controller",
    "networked-el-hinf",
    NetworkedElHinfSection,
    _build,
    "Mehrabian distributed H-infinity attitude synchronisation with adaptive fault recovery "
    "(3-2-1 Euler angles, generalised torque)",
)
