"""Distributed H-infinity synchronisation / tracking law for networked Euler-Lagrange attitudes with
adaptive fault recovery (Mehrabian et al. (6), (8), (18)-(19); equations in
:mod:`formation_ftc.blocks.controllers.networked_el_hinf`).

Measurement (flight side): the attitude of every spacecraft as a dict ``{"q": (m, 3) Euler angles
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

Fault recovery: the estimator's :class:`~formation_ftc.blocks.fdi.FDIOutput` (flag, u*) drives
Gamma (18) and the adaptive estimate u^ (19); without an estimator both are zero (no reconfiguration).
"""

from __future__ import annotations

from typing import Any, Literal

import jax
import jax.numpy as jnp

from formation_ftc.blocks.controllers.networked_el_hinf import (
    ELHinfConfig,
    adaptation_rate,
    control,
)
from formation_ftc.components.expressions import vector_expression
from formation_ftc.core.dynamics.euler_lagrange import euler_rates_from_body_rates
from formation_ftc.sim.components import Controller, FlightInputs, Signal, component, static

__all__ = ["NetworkedElHinfController"]

VEC = ("spacecraft", "axis")


@component
class NetworkedElHinfController(Controller):
    """Law (6)+(8)+(18) with the adaptation (19), continuous (evaluated at every RK stage).

    Leaves (per spacecraft and channel unless stated): ``K`` [N m s], ``K_P`` [1/s], ``K_I`` [1/s^2],
    ``sigma``, ``e_gain`` [1/s] (m, 3); ``alpha``, ``gamma`` (m,) [-]; ``phi_b`` boundary layer
    [rad/s]; ``avg`` (m, m) row-normalised adjacency; ``J_hat`` (m, 3, 3) nominal inertia [kg m^2].
    Static: ``law``, ``compensation`` (see :class:`~formation_ftc.blocks.controllers.networked_el_hinf.ELHinfConfig`),
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
    phi_b: Any = None
    avg: Any = None
    J_hat: Any = None
    law: Literal["literal", "diffusive"] = static(default="literal")
    compensation: Literal["sat", "sign", "certainty_equivalence"] = static(default="sat")
    desired_attitude: tuple[str, str, str] = static(default=("0", "0", "0"))
    links: tuple[tuple[int, int], ...] = static(default=())

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
        p = {
            "K": self.K,
            "K_P": self.K_P,
            "K_I": self.K_I,
            "alpha": self.alpha,
            "gamma": self.gamma,
            "phi_b": self.phi_b,
            "avg": self.avg,
        }
        ctl = control(
            q,
            qdot,
            state["z"],
            state["u_hat"],
            flag,
            d["e"],
            d["e_dot"],
            d["e_ddot"],
            self.J_hat,
            p,
            ELHinfConfig(self.law, self.compensation),
        )  # (6) + (8) + (18)
        u_hat_dot = adaptation_rate(
            ctl.s, state["u_hat"], u_star, flag, self.sigma, self.e_gain
        )  # (19)
        qt = ctl.q_tilde
        outputs = {
            "sliding_variable": ctl.s,
            "fault_estimate_adaptive": state["u_hat"],
            "tracking_error": qt,
        }
        if self.links:
            j = jnp.asarray([a for a, _ in self.links])
            n = jnp.asarray([b for _, b in self.links])
            outputs["synchronisation_error"] = qt[j] - qt[n]
        return ctl.u, {"z": qt, "u_hat": u_hat_dot}, outputs

    def signals(self):
        sig = (
            Signal("sliding_variable", VEC, "rad s-1", "sliding variable s = q_dot - r"),
            Signal("fault_estimate_adaptive", VEC, "N m", "adaptive fault estimate u^ of (19)"),
            Signal("tracking_error", VEC, "rad", "tracking error q - e (measured)"),
        )
        if self.links:
            sig += (
                Signal(
                    "synchronisation_error",
                    ("link", "axis"),
                    "rad",
                    "tracking-error difference q~_j - q~_n over each undirected link",
                ),
            )
        return sig

    def coords(self):
        return {"link": [f"{a + 1}-{b + 1}" for a, b in self.links]} if self.links else {}
