"""The iterative learning observer (ILO) of Gui et al. 2022 as an estimator component."""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp

from formation_ftc.blocks.observers.iterative_learning_observer import (
    ilo_learning_update,
    ilo_propagate,
)
from formation_ftc.core.delay_line import delay_init, delay_push, delay_read
from formation_ftc.core.dynamics.cw import cw_matrices_jax
from formation_ftc.sim.components import Estimator, FlightInputs, Signal, component, static

__all__ = ["IterativeLearningObserver"]

STATE = ("spacecraft", "component")
VEC = ("spacecraft", "axis")


@component
class IterativeLearningObserver(Estimator):
    """ILO (5) on a CW model per spacecraft: reconstructs the thruster faults F [m/s^2] from the
    measured (N, 6) relative state y (C = I6) and the commanded acceleration u.

    Measurement update at t_k (:meth:`update`)::

        e_y,k = y_k - q_hat_k;   F_hat_k = Q1 F_hat_{k-m} + Q2 L2 e_y,k                    # (5)

    time update over the step (:meth:`predict`, forward Euler with u_k, F_hat_k, e_y,k held)::

        q_hat_{k+1} = q_hat_k + dt (A q_hat_k + B u_k + H F_hat_k + L1 e_y,k + gamma sgn e_y,k)   # (5)

    with A = A(n) and B = H = [0; I3] of the CW model (mean motion ``mean_motion`` [rad/s]); the learning
    interval tau = m dt (``learning_steps`` = m); ``sign_term = False`` drops gamma sgn (ILO of ref. [25]).
    Gains: L1 (6, 6) [1/s], L2 (3, 6) [1/s], Q1 (3,) [-], Q2 [-], gamma [m/s^2].

    The estimate (``FlightInputs.estimate`` of the controller) is ``{"fault": F_hat_k (N, 3), "state":
    q_hat_k (N, 6), "output_error": e_y,k (N, 6)}``. Recorded: ``estimate``, ``fault_estimate``,
    ``estimation_error`` (e_y = y - q_hat), ``estimation_error_sign`` (sgn e_y) and
    ``fault_estimate_mean``, the mean of F_hat over the ``mean_steps`` steps before the sample (with
    the sign term F_hat chatters with a period of 2 steps, which decimated samples would alias).
    """

    count: int = static()
    mean_motion: Any = 0.0  # n of the CW model [rad/s]
    L1: Any = 0.0  # (6, 6) [1/s]
    L2: Any = 0.0  # (3, 6) [1/s]
    Q1: Any = 1.0  # (3,) diagonal [-]
    Q2: Any = 1.0  # [-]
    gamma: Any = 0.0  # [m/s^2]
    initial_estimate: Any = 0.0  # q_hat(0), (N, 6) [m, m/s]
    fault_prehistory: Any = 0.0  # F_hat(t), t < 0, (N, 3) [m/s^2]
    learning_steps: int = static(default=1)  # m = tau / dt
    sign_term: bool = static(default=True)
    mean_steps: int = static(
        default=1
    )  # steps averaged by fault_estimate_mean (the record interval)

    def initial_state(self, measurement0):
        n = self.count
        return dict(
            q_hat=jnp.asarray(self.initial_estimate, dtype=jnp.float64),
            F_hist=delay_init(self.fault_prehistory, self.learning_steps),
            F_hat=jnp.zeros((n, 3)),
            e_y=jnp.zeros((n, 6)),
            mean_sum=jnp.zeros((n, 3)),
            mean_last=jnp.zeros((n, 3)),
            mean_n=jnp.zeros((), dtype=jnp.int32),
        )

    def update(self, t, state, inputs: FlightInputs):
        e_y = inputs.measurement - state["q_hat"]  # C = I6
        F_hat = ilo_learning_update(
            delay_read(state["F_hist"], self.learning_steps), e_y, self.Q1, self.Q2, self.L2
        )  # (5)
        n = state["mean_n"]
        first, full = n == 0, n == self.mean_steps
        reset = first | full
        mean_last = jnp.where(
            first, F_hat, jnp.where(full, state["mean_sum"] / self.mean_steps, state["mean_last"])
        )
        new = dict(
            q_hat=state["q_hat"],
            F_hist=delay_push(state["F_hist"], F_hat, self.learning_steps),
            F_hat=F_hat,
            e_y=e_y,
            mean_sum=jnp.where(reset, 0.0, state["mean_sum"]) + F_hat,
            mean_last=mean_last,
            mean_n=jnp.where(reset, 1, n + 1).astype(jnp.int32),
        )
        return new, self._estimate(new)

    def predict(self, t, state, command, dt):
        A, B = cw_matrices_jax(self.mean_motion)
        q_hat = ilo_propagate(
            state["q_hat"],
            command,
            state["F_hat"],
            state["e_y"],
            A,
            B,
            B,
            self.L1,
            self.gamma,
            dt,
            self.sign_term,
        )  # (5), H = B
        return {**state, "q_hat": q_hat}

    def _estimate(self, state):
        return {"fault": state["F_hat"], "state": state["q_hat"], "output_error": state["e_y"]}

    def signals(self):
        return (
            Signal(
                "estimate",
                STATE,
                "m, m s-1",
                "ILO state estimate q_hat (positions [m], velocities [m s-1])",
                "LVLH",
            ),
            Signal(
                "estimation_error",
                STATE,
                "m, m s-1",
                "e_y = y - q_hat (= q - q_hat with exact measurements)",
                "LVLH",
            ),
            Signal("estimation_error_sign", STATE, "1", "sgn(e_y), the switching term of the ILO"),
            Signal("fault_estimate", VEC, "m s-2", "reconstructed fault F_hat", "LVLH"),
            Signal(
                "fault_estimate_mean",
                VEC,
                "m s-2",
                "F_hat averaged over the record interval "
                "(removes the period-2-step chatter caused by the sign term)",
                "LVLH",
            ),
        )

    def outputs(self, t, state, estimate):
        return {
            "estimate": estimate["state"],
            "estimation_error": estimate["output_error"],
            "estimation_error_sign": jnp.sign(estimate["output_error"]),
            "fault_estimate": estimate["fault"],
            "fault_estimate_mean": state["mean_last"],
        }
