"""Plant ``switched-formation``: N_max spacecraft slots whose members change at prescribed switches
(Yang2013's state-varying switched formation at the closed-loop error level).

Truth side of the switched formation: every slot holds the 13-dimensional error state (7)
``x_i = [e_R, e_V, e_omega, e_q, e_q4]`` of one spacecraft (desired minus actual, in its body frame
F_i). The closed-loop error dynamics (2), (5) are exact for any orbit once the laws (12)-(13) cancel
the known drift terms Phi_i, Upsilon_i (Yang2013 E001-02), so the drift is zero on both sides: the
translational part is :func:`formation_ftc.core.dynamics.tracking_error.translational_error_rates`
and the attitude part the rigid body of
:func:`formation_ftc.core.dynamics.attitude_quaternion.rigid_body_quaternion_rates` without
gyroscopic term.

Membership is a decision of the supervisor (:class:`~formation_ftc.components.supervisors.switching.SwitchDecision`):
slots outside the formation are frozen (their rates are masked), and at the end of a step after which
a new mode starts the state jumps by the variation model (10), ``X <- (P_j (x) I_13) X + X*_j``, with
``P_j`` the mode's variation matrix S_ij placed on the slots and ``X*_j`` the new states of the
spacecraft that join. The state before the jump (its per-spacecraft norms) is kept, so the norms at
the left limit t_k^- of every switch are recorded and enter the every-step metrics.

The plan (switch times, members, variation, new states) is the ``[supervisor]``'s mode sequence: the
plant needs the capability ``switching-plan`` (``supervisor type = "switching"``) and provides
``error-state``.
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np
from pydantic import Field, PositiveFloat

from formation_ftc.components._registry import BuildContext, builder_input, per_spacecraft, register
from formation_ftc.components._sections import STATE_DIM, ErrorState, Vec3Expr, expression_text
from formation_ftc.components.expressions import vector_expression
from formation_ftc.config.base import StrictModel
from formation_ftc.core.dynamics.attitude_quaternion import rigid_body_quaternion_rates
from formation_ftc.core.dynamics.tracking_error import translational_error_rates
from formation_ftc.sim.components import Plant, Signal, TruthInputs, component, static
from formation_ftc.sim.contract import STATE, VEC, as_float

__all__ = [
    "SwitchedFormationPlant",
    "SwitchedFormationSection",
    "ErrorState",
    "ERROR_COMPONENTS",
    "STATE_DIM",
    "input_norm",
]

ERROR_COMPONENTS = [
    *(f"e_{part}_{axis}" for part in ("R", "V", "w") for axis in "xyz"),
    *(f"e_q_{k}" for k in "1234"),
]


def input_norm(f, tau):
    """``|u_i| = |[f; tau]|`` of (7) (N and N m combined, as in the paper's Fig. 5).

    Parameters
    ----------
    f : array_like, shape (..., 3)
        Force [N].
    tau : array_like, shape (..., 3)
        Torque [N m].

    Returns
    -------
    jax.Array
        |u_i|, shape (...,).

    Examples
    --------
    >>> import numpy as np
    >>> float(input_norm(np.array([3.0, 0, 0]), np.array([0, 4.0, 0])))
    5.0
    """
    return jnp.sqrt(jnp.sum(f * f, axis=-1) + jnp.sum(tau * tau, axis=-1))


def _active(decision, count: int):
    """Membership mask (N,) of the decision in force (every slot when there is no supervisor)."""
    active = getattr(decision, "active", None)
    return jnp.ones(count) if active is None else active


@component
class SwitchedFormationPlant(Plant):
    """Error-level 6-DOF closed-loop plant of N_max spacecraft slots driven by a wrench [f, tau] (N, 6)
    [N, N m] (see module docstring).

    ``mass`` (N,) [kg]; ``inertia`` J (3, 3) [kg m^2] of every spacecraft; ``initial_error``
    (N, 13) x_i(0) = [e_R, e_V, e_omega, e_q, e_q4] [m, m/s, rad/s, -]; ``variation`` (n_modes, N, N) slot maps P_j of
    (10) (P_0 unused); ``new_states`` (n_modes, N, 13) X*_j; ``disturbance_force`` d_i(t) [N] and
    ``disturbance_torque`` iota_i(t) [N m] (expressions in t [s] and i); ``rotation_coupling``: keep the
    norm-preserving omega_i x e terms of (2) with omega_i = -e_omega (reference at rest).
    """

    quantity = "wrench"

    mass: Any
    inertia: Any
    initial_error: Any
    variation: Any
    new_states: Any
    disturbance_force: tuple[str, str, str] = static(default=("0", "0", "0"))
    disturbance_torque: tuple[str, str, str] = static(default=("0", "0", "0"))
    rotation_coupling: bool = static(default=True)

    @property
    def count(self) -> int:
        return int(np.shape(self.mass)[0])

    def initial_state(self):
        x0 = jnp.asarray(self.initial_error)
        return {"x": x0, "left_norm": jnp.linalg.norm(x0, axis=-1)}

    def exogenous(self, t):
        return {
            "d": vector_expression(self.disturbance_force, "disturbance.force", t, self.count),
            "iota": vector_expression(self.disturbance_torque, "disturbance.torque", t, self.count),
        }

    def derivative(self, t, x, inputs: TruthInputs):
        X = x["x"]
        e_R, e_V, e_w, e_q = X[:, 0:3], X[:, 3:6], X[:, 6:9], X[:, 9:13]
        f, tau = inputs.force[:, :3], inputs.force[:, 3:]
        # drift Phi_i, Upsilon_i: cancelled exactly by (12)-(13) (E001-02)
        zero = jnp.zeros_like(e_R)
        omega = -e_w if self.rotation_coupling else None  # omega_i = -e_omega, reference at rest
        de_R, de_V = translational_error_rates(
            e_R, e_V, zero, f, inputs.exogenous["d"], self.mass[:, None], omega
        )  # Yang2013 eq. (2)
        dw, dq = rigid_body_quaternion_rates(
            e_w, e_q, tau + inputs.exogenous["iota"], self.inertia, gyroscopic=False
        )  # Yang2013 eq. (5): no gyroscopic term (part of the drift Upsilon the law (13) cancels)
        dx = jnp.concatenate([de_R, de_V, dw, dq], axis=-1)
        active = _active(inputs.decision, self.count)[:, None]
        return {"x": dx * active, "left_norm": jnp.zeros(self.count)}

    def jump(self, t, x, decision):
        X = x["x"]
        left = jnp.linalg.norm(X, axis=-1)
        mode = getattr(decision, "mode", None)
        if mode is None:
            return {"x": X, "left_norm": left}
        nxt = decision.next_mode
        # Yang2013 eq. (10)
        switched = jnp.einsum("ab,bc->ac", self.variation[nxt], X) + self.new_states[nxt]
        return {"x": jnp.where(nxt != mode, switched, X), "left_norm": left}

    def signals(self):
        sc = ("spacecraft",)
        return (
            Signal(
                "error_state",
                STATE,
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
                VEC,
                "m",
                "relative position R~ = R~^d - e_R (0 outside the formation)",
                "F_i",
            ),
        )

    def coords(self):
        return {"component": ERROR_COMPONENTS}

    def needs(self) -> dict[str, str]:
        return {"switching-plan": "execute membership and the state variation (10) at its switches"}

    def provides(self) -> frozenset[str]:
        return frozenset({"error-state"})

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


# ------------------------------------------------------------------------------------------ section
PositiveVec3 = tuple[PositiveFloat, PositiveFloat, PositiveFloat]


class SwitchedFormationSection(StrictModel):
    """Truth of the switched formation: slots, masses, inertia, disturbances, initial error states."""

    count: int = builder_input(
        ge=1, le=64, description="Number of spacecraft slots N_max (numbered 1..count) [-]."
    )
    mass: float = Field(
        150.0,
        gt=0,
        description="True mass M_i of every spacecraft [kg] (the laws use their stated "
        "controller.nominal_mass).",
    )
    inertia: PositiveVec3 = Field(
        (25.0, 25.0, 25.0),
        description="True principal inertia diag(J_i) of every spacecraft [kg m^2] (the laws use "
        "their stated controller.nominal_inertia).",
    )
    rotation_coupling: bool = Field(
        True,
        description="Keep the norm-preserving omega_i x e terms of (2) with omega_i = -e_omega "
        "(reference at rest); false drops them (the terms preserve the error norm).",
    )
    disturbance_force: Vec3Expr = Field(
        ("0", "0", "0"),
        description="Disturbance force d_i(t) per axis; expressions in t [s] and i [N].",
    )
    disturbance_torque: Vec3Expr = Field(
        ("0", "0", "0"),
        description="Disturbance torque iota_i(t) per axis; expressions in t [s] and i [N m].",
    )
    initial_state: list[ErrorState] = builder_input(
        description="x_i(0) of the first mode's members (the other slots start at 0)."
    )


def _build(sec: SwitchedFormationSection, ctx: BuildContext) -> SwitchedFormationPlant:
    """The plant of a validated ``[plant] type = "switched-formation"`` section: the plan is the
    ``[supervisor]``'s mode sequence (without one: a single mode, and the loop is refused for the
    missing ``switching-plan``)."""
    from formation_ftc.components.supervisors.switching import (
        SwitchingSupervisorSection,
        switched_structure,
    )

    plan = ctx.section("supervisor")
    x0 = np.zeros((sec.count, STATE_DIM))
    for init in sec.initial_state:
        x0[init.spacecraft - 1] = init.vector()
    if isinstance(plan, SwitchingSupervisorSection):
        st = switched_structure(plan, sec.count, ctx.dt)
        first = sorted(s.spacecraft for s in sec.initial_state)
        if first != sorted(x for x in plan.modes[0].members if x > 0):
            raise ValueError(
                f"plant.initial_state must give exactly the members of supervisor.modes[0] "
                f"{plan.modes[0].members}, got spacecraft {first}"
            )
        variation, new_states = st.P, st.xstar
    else:  # a placeholder of one mode: validation names the missing plan
        variation = np.eye(sec.count)[None]
        new_states = np.zeros((1, sec.count, STATE_DIM))
    return SwitchedFormationPlant(
        mass=as_float(per_spacecraft(sec.mass, sec.count, "plant.mass")),
        inertia=as_float(np.diag(sec.inertia)),
        initial_error=as_float(x0),
        variation=as_float(variation),
        new_states=as_float(new_states),
        disturbance_force=expression_text(sec.disturbance_force),
        disturbance_torque=expression_text(sec.disturbance_torque),
        rotation_coupling=sec.rotation_coupling,
    )


register(
    "plant",
    "switched-formation",
    SwitchedFormationSection,
    _build,
    "Yang2013 error dynamics (2), (5) of N_max slots, membership and state variation (10) at the "
    "plan's switches",
)
