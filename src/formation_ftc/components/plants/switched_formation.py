"""A formation of N_max spacecraft slots whose members change at prescribed switches (Yang2013).

Truth side of the state-varying switched formation: every slot holds the 13-dimensional error state
(7) ``x_i = [e_R, e_V, e_omega, e_q, e_q4]`` of one spacecraft (desired minus actual, in its body
frame F_i). The closed-loop error dynamics (2), (5) are exact for any orbit once the laws (12)-(13)
cancel the known drift terms Phi_i, Upsilon_i (Yang2013 E001-02), so the drift is zero on both sides:
the translational part is :func:`formation_ftc.core.dynamics.tracking_error.translational_error_rates`
and the attitude part a :class:`~formation_ftc.components.plants.quaternion_rigid_body.QuaternionRigidBodyPlant`
without gyroscopic term.

Membership is a decision of the supervisor (:class:`~formation_ftc.components.supervisors.switching_supervisor.SwitchDecision`):
slots outside the formation are frozen (their rates are masked), and at the end of a step after which
a new mode starts the state jumps by the variation model (10), ``X <- (P_j (x) I_13) X + X*_j``, with
``P_j`` the mode's variation matrix S_ij placed on the slots and ``X*_j`` the new states of the
spacecraft that join. The state before the jump (its per-spacecraft norms) is kept, so the norms at
the left limit t_k^- of every switch are recorded and enter the every-step metrics.
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np

from formation_ftc.blocks.controllers.yang2013_individual import input_norm
from formation_ftc.components.expressions import vector_expression
from formation_ftc.components.plants.quaternion_rigid_body import QuaternionRigidBodyPlant
from formation_ftc.core.dynamics.tracking_error import translational_error_rates
from formation_ftc.sim.components import Plant, Signal, TruthInputs, component, static

__all__ = ["SwitchedFormationPlant", "ERROR_COMPONENTS", "STATE_DIM"]

ERROR_COMPONENTS = [
    "e_R_x",
    "e_R_y",
    "e_R_z",
    "e_V_x",
    "e_V_y",
    "e_V_z",
    "e_w_x",
    "e_w_y",
    "e_w_z",
    "e_q_1",
    "e_q_2",
    "e_q_3",
    "e_q_4",
]
STATE_DIM = 13  # x_i = [e_R, e_V, e_w, e_q, e_q4] (7)


def _active(decision, count: int):
    """Membership mask (N,) of the decision in force (every slot when there is no supervisor)."""
    active = getattr(decision, "active", None)
    return jnp.ones(count) if active is None else active


@component
class SwitchedFormationPlant(Plant):
    """Error-level 6-DOF closed-loop plant of N_max spacecraft slots driven by a wrench [f, tau] (N, 6)
    [N, N m] (see module docstring).

    ``mass`` (N,) [kg]; ``attitude`` the attitude part (its inertia [kg m^2], initial e_omega, (e_q,
    e_q4) and disturbance torque iota(t) [N m]); ``initial_translation`` (N, 6) [e_R, e_V] [m, m/s];
    ``variation`` (n_modes, N, N) slot maps P_j of (10) (P_0 unused); ``new_states`` (n_modes, N, 13)
    X*_j; ``disturbance_force`` d_i(t) [N] (expressions in t [s] and i); ``rotation_coupling``: keep the
    norm-preserving omega_i x e terms of (2) with omega_i = -e_omega (reference at rest).
    """

    quantity = "wrench"

    mass: Any
    attitude: QuaternionRigidBodyPlant
    initial_translation: Any
    variation: Any
    new_states: Any
    disturbance_force: tuple[str, str, str] = static(default=("0", "0", "0"))
    rotation_coupling: bool = static(default=True)

    @property
    def count(self) -> int:
        return int(np.shape(self.mass)[0])

    def initial_state(self):
        att = self.attitude.initial_state()
        x0 = jnp.concatenate([self.initial_translation, att["omega"], att["q"]], axis=-1)
        return {"x": x0, "left_norm": jnp.linalg.norm(x0, axis=-1)}

    def exogenous(self, t):
        return {
            "d": vector_expression(self.disturbance_force, "disturbance.force", t, self.count),
            "attitude": self.attitude.exogenous(t),
        }

    def derivative(self, t, x, inputs: TruthInputs):
        X = x["x"]
        e_R, e_V, e_w, e_q = X[:, 0:3], X[:, 3:6], X[:, 6:9], X[:, 9:13]
        f, tau = inputs.force[:, :3], inputs.force[:, 3:]
        zero = jnp.zeros_like(
            e_R
        )  # drift Phi_i, Upsilon_i: cancelled exactly by (12)-(13) (E001-02)
        omega = (
            -e_w if self.rotation_coupling else None
        )  # omega_i = -e_omega with the reference at rest
        de_R, de_V = translational_error_rates(
            e_R, e_V, zero, f, inputs.exogenous["d"], self.mass[:, None], omega
        )  # Yang2013 eq. (2)
        att = self.attitude.rates(
            {"omega": e_w, "q": e_q}, tau + inputs.exogenous["attitude"]["iota"]
        )  # Yang2013 eq. (5)
        dx = jnp.concatenate([de_R, de_V, att["omega"], att["q"]], axis=-1)
        return {
            "x": dx * _active(inputs.decision, self.count)[:, None],
            "left_norm": jnp.zeros(self.count),
        }

    def jump(self, t, x, decision):
        X = x["x"]
        left = jnp.linalg.norm(X, axis=-1)
        mode = getattr(decision, "mode", None)
        if mode is None:
            return {"x": X, "left_norm": left}
        nxt = decision.next_mode
        switched = (
            jnp.einsum("ab,bc->ac", self.variation[nxt], X) + self.new_states[nxt]
        )  # Yang2013 eq. (10)
        return {"x": jnp.where(nxt != mode, switched, X), "left_norm": left}

    def signals(self):
        sc = ("spacecraft",)
        return (
            Signal(
                "error_state",
                ("spacecraft", "component"),
                "1",
                "error state x_i (7), desired minus actual (m, m s-1, rad s-1, 1 by component)",
                "F_i",
            ),
            Signal("state_norm", (), "1", "|X_sigma(t)(t)|, norm of the stacked error states"),
            Signal(
                "state_norm_left",
                (),
                "1",
                "|X(t_k^-)|, norm before the state variation (10) at t_k",
            ),
            Signal("state_norm_peak", (), "1", "max(|X(t_k^-)|, |X(t_k)|)"),
            Signal("spacecraft_norm", sc, "1", "|x_i|"),
            Signal(
                "spacecraft_norm_left",
                sc,
                "1",
                "|x_i(t_k^-)|, before the state variation (10) at t_k",
            ),
            Signal(
                "input_norm",
                sc,
                "1",
                "|u_i| = |[f_i; tau_i]| of the applied inputs (N and N m "
                "combined, as in Yang2013 Fig. 5); 0 outside the formation",
            ),
            Signal(
                "relative_position",
                ("spacecraft", "axis"),
                "m",
                "relative position R~ = R~^d - e_R (0 outside the formation)",
                "F_i",
            ),
        )

    def coords(self):
        return {"component": ERROR_COMPONENTS}

    def outputs(self, t, x, inputs):
        X = x["x"]
        active = _active(inputs.decision, self.count)
        norm = jnp.linalg.norm(X)
        norm_left = jnp.sqrt(jnp.sum(x["left_norm"] ** 2))
        desired = getattr(inputs.decision, "desired_position", None)
        desired = jnp.zeros((self.count, 3)) if desired is None else desired
        return {
            "error_state": X,
            "state_norm": norm,
            "state_norm_left": norm_left,
            "state_norm_peak": jnp.maximum(norm, norm_left),
            "spacecraft_norm": jnp.linalg.norm(X, axis=-1),
            "spacecraft_norm_left": x["left_norm"],
            "input_norm": input_norm(inputs.force[:, :3], inputs.force[:, 3:]) * active,
            "relative_position": (desired - X[:, 0:3]) * active[:, None],
        }
