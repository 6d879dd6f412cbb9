"""Controller ``gui2022-lof2tc``: the learning output-feedback fault-tolerant tracking controller
(LOF2TC) of Gui et al. 2022, eqs. (30)-(32), an acceleration law on a CW nominal orbit.

With the tracking error ``e_q = q0 - q`` and ``e_y = C e_q`` (29)::

    pi(t) = G1 pi(t - tau) + G2 e_q^T (K C)^T (K C) e_q                 # (31), uses K C e_q = K e_y
    v(t)  = G3 v(t - tau) + G4 K e_q(t)                                 # (32), K e_q := K e_y (C = I)
    u     = pi(t) K e_y - B^+ E v(t) - B^+ H F_hat(t)                   # (30)

``F_hat`` comes from the iterative learning observer (5). Discrete implementation: the
learning laws are recursions evaluated once per sample with ``tau = m dt`` (m integer >= 1); the caller
keeps the past values (:mod:`formation_ftc.core.delay_line`; prehistory ``pi(-tau) = pi_init``
[CHOICE, E002-08: so that pi >= 1/2 initially], ``v(-tau) = v_init``).

Every function acts on the last axis and broadcasts over leading axes (one row per spacecraft).
Units: e_y in [m, m/s], K in [1/s^2, 1/s], u, v, F_hat in m/s^2 (per unit mass, E002-03), pi [-];
``G1`` [-], ``G2`` [s^4/m^2] (so that pi is dimensionless), ``G3`` (m,) diagonal [-], ``G4`` [-],
``BpE`` = B^+ E and ``BpH`` = B^+ H (m, m).

What the Gui2022 laws share (the nominal orbit, the on-board CW model, acceleration -> force, the
gains) is in :mod:`formation_ftc.components.controllers._output_feedback`. LOF2TC compensates the fault
estimate of an estimator (the capability ``thruster-fault-estimate``, the
``iterative-learning-observer``).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from pydantic import Field

from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.components._sections import Vec3, section_floats
from formation_ftc.components.controllers._output_feedback import (
    NominalOrbitTracking,
    OutputFeedbackSection,
    _on_plant,
    _output_feedback_fields,
)
from formation_ftc.components.estimators.iterative_learning_observer import learning_steps
from formation_ftc.core.delay_line import delay_init, delay_push, delay_read
from formation_ftc.core.linear import matvec
from formation_ftc.sim.components import Controller, FlightInputs, Signal, component, static
from formation_ftc.sim.contract import VEC, as_float

__all__ = ["lof2tc_law", "LearningOutputFeedbackController", "Lof2tcSection"]


def lof2tc_law(
    e_y: jax.Array,
    F_hat: jax.Array,
    pi_past: jax.Array,
    v_past: jax.Array,
    K,
    G1,
    G2,
    G3,
    G4,
    BpE,
    BpH,
) -> tuple[jax.Array, jax.Array, jax.Array]:
    """``(u, pi, v)`` of (30)-(32) at the current sample.

    Parameters
    ----------
    e_y : jax.Array, shape (..., p)
        Measured tracking error [m, m/s].
    F_hat : jax.Array, shape (..., m)
        Fault estimate [m/s^2].
    pi_past : jax.Array, shape (...,)
        pi(t - tau) [-].
    v_past : jax.Array, shape (..., m)
        v(t - tau) [m/s^2].
    K : array_like, shape (m, p)
        Gain [1/s^2, 1/s].
    G1, G2, G3, G4
        Learning gains of (31)-(32): G1 [-], G2 [s^4/m^2], G3 (m,) [-], G4 [-].
    BpE, BpH : array_like, shape (m, m)
        B^+ E and B^+ H [-].

    Returns
    -------
    tuple of jax.Array
        u (..., m) [m/s^2], pi (...,) [-], v (..., m) [m/s^2].

    Examples
    --------
    >>> import numpy as np
    >>> K = np.hstack([np.eye(3), np.zeros((3, 3))])
    >>> u, pi, v = lof2tc_law(np.array([1.0, 0, 0, 0, 0, 0]), np.zeros(3), 1.0, np.zeros(3), K,
    ...                       1.0, 0.5, np.ones(3), -1.0, np.eye(3), np.eye(3))
    >>> float(pi), np.asarray(v).tolist(), np.asarray(u).tolist()  # pi = 1 + 0.5, v = -K e, u = pi K e - v
    (1.5, [-1.0, 0.0, 0.0], [2.5, 0.0, 0.0])
    """
    Ke = matvec(K, e_y)
    pi = G1 * pi_past + G2 * jnp.sum(Ke * Ke, axis=-1)  # (31)
    v = G3 * v_past + G4 * Ke  # (32)
    u = pi[..., None] * Ke - matvec(BpE, v) - matvec(BpH, F_hat)  # (30)
    return u, pi, v


@component
class LearningOutputFeedbackController(NominalOrbitTracking):
    """LOF2TC (30)-(32) per spacecraft::

        pi_k = G1 pi_{k-m} + G2 |K e_y|^2,   v_k = G3 v_{k-m} + G4 K e_y,
        u_k  = pi_k K e_y - B^+E v_k - B^+H F_hat_k                                [m/s^2]

    Gains K (3, 6) [1/s^2, 1/s], G1 [-], G2 [s^4/m^2], G3 (3,) [-], G4 [-], BpE = B^+ E and BpH = B^+ H
    (3, 3); learning interval tau = m dt (``learning_steps``); prehistories ``pi_initial`` (N,) [-] and
    ``v_initial`` (N, 3) [m/s^2] (E002-08). State: the delay lines of pi and v."""

    K: Any = 0.0
    G1: Any = 0.0
    G2: Any = 0.0
    G3: Any = 0.0
    G4: Any = 0.0
    BpE: Any = 0.0
    BpH: Any = 0.0
    pi_initial: Any = 1.0  # (N,)
    v_initial: Any = 0.0  # (N, 3)
    learning_steps: int = static(default=1)

    def initial_state(self):
        m = self.learning_steps
        return {"pi": delay_init(self.pi_initial, m), "v": delay_init(self.v_initial, m)}

    def output(self, t, state, inputs: FlightInputs):
        m = self.learning_steps
        q0, e_y, F_hat = self.tracking(inputs)
        pi_past, v_past = delay_read(state["pi"], m), delay_read(state["v"], m)  # at k - m
        u, pi, v = lof2tc_law(
            e_y,
            F_hat,
            pi_past,
            v_past,
            self.K,
            self.G1,
            self.G2,
            self.G3,
            self.G4,
            self.BpE,
            self.BpH,
        )  # (30)-(32)
        nxt = {"pi": delay_push(state["pi"], pi, m), "v": delay_push(state["v"], v, m)}
        out = {"desired_state": q0, "tracking_error": e_y, "learning_gain": pi, "compensation": v}
        return u, nxt, out

    def signals(self):
        return super().signals() + (
            Signal("learning_gain", ("spacecraft",), "1", "learning gain pi (31)"),
            Signal("compensation", VEC, "m s-2", "learning compensation v (32)", "LVLH"),
        )

    def needs(self) -> dict[str, str]:
        return {**super().needs(), "thruster-fault-estimate": "compensate it (-B^+H F_hat in (30))"}


class Lof2tcSection(OutputFeedbackSection):
    """LOF2TC (30)-(32): u = pi K e_y - B^+E v - B^+H F_hat with the learning gain pi and compensation v."""

    G1: float = Field(description="G1 of (31) [-].")
    G2: float = Field(description="G2 of (31) [s^4/m^2].")
    G3: Vec3 = Field(description="Diagonal of G3 in (32) [-].")
    G4: float = Field(description="G4 of (32) [-].")
    l: float = builder_input(
        1.0, gt=0, description="l of (43), G2 = 1/(l (1 + mu1)) [-] (for `check`; Gui2022: 1)."
    )
    mu1: float = builder_input(
        1e-4, gt=0, description="mu1 of Theorem 2 [-] (for `check`; Gui2022: 1e-4)."
    )
    beta1: float = builder_input(
        1.0,
        gt=0,
        description="beta1 of (43), G4 = -1/(beta1 (1 + mu1)) [-] (for `check`; Gui2022: 1).",
    )
    gamma2: float = builder_input(
        9e-4, gt=0, description="gamma2 of (37) [-] (for `check`; Gui2022: 9e-4)."
    )
    gamma3: float = builder_input(
        9e-4, gt=0, description="gamma3 of (36) [-] (for `check`; Gui2022: 9e-4)."
    )
    pi_initial: float = Field(1.0, description="pi(-tau) [-].")
    v_initial: Vec3 = Field((0.0, 0.0, 0.0), description="v(-tau) [m/s^2].")
    learning_interval: float = builder_input(
        gt=0, description="tau of (31)-(32): a positive integer multiple of simulation.dt [s]."
    )


def _build(sec: Lof2tcSection, ctx: BuildContext) -> Controller:
    """The controller of a validated ``[controller] type = "gui2022-lof2tc"`` section."""
    common = _output_feedback_fields(sec, ctx)
    N = ctx.count
    law = LearningOutputFeedbackController(
        **common,
        **section_floats(sec, "G1", "G2", "G3", "G4"),
        BpE=common["BpH"],
        pi_initial=as_float(np.full(N, sec.pi_initial)),
        v_initial=as_float(np.broadcast_to(np.asarray(sec.v_initial, float), (N, 3)).copy()),
        learning_steps=learning_steps(
            sec.learning_interval, ctx.dt, "controller.learning_interval"
        ),
    )
    return _on_plant(law, sec, ctx)


register(
    "controller",
    "gui2022-lof2tc",
    Lof2tcSection,
    _build,
    "Gui2022 LOF2TC (30)-(32): learning output feedback on a CW nominal orbit (acceleration law)",
)
