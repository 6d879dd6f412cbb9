"""A relative navigation filter: a linear Kalman filter on the measured LVLH relative states."""

from __future__ import annotations

from typing import Any, NamedTuple

import jax.numpy as jnp

from formation_ftc.sim.components import Estimator, FlightInputs, Signal, component, static

__all__ = ["RelativeNavigationFilter", "NavigationState"]

STATE = ("spacecraft", "component")


class NavigationState(NamedTuple):
    x_hat: Any  # (N, 6) estimate [m, m/s]
    p: Any  # (6, 6) error covariance (one model and one noise for every spacecraft)


@component
class RelativeNavigationFilter(Estimator):
    """Kalman filter of every spacecraft's relative state ``q = [rho, rho']`` (LVLH) from the sensors'
    noisy measurement ``y_k = q_k + v_k``, ``v_k ~ N(0, r)``, with the on-board linear model
    (:func:`formation_ftc.design.kalman.discrete_model`)::

        q_{k+1} = phi q_k + gamma f_k / m_nom + w_k,   w_k ~ N(0, qd)

    driven by the controller's command ``f_k`` [N] held over the step, per unit of the stated nominal
    mass ``nominal_mass`` (N,) [kg]. At every step: measurement update at t_k (Joseph form), then, after
    the control step, time update to t_{k+1}. It is a navigation filter (``navigation = True``): the
    controller reads its estimate in place of the measurement, held over the step. It starts from the
    first measurement with covariance ``p0``. Records ``navigation_estimate`` (N, 6) and
    ``navigation_sigma`` (6,), the filter's own standard deviations (flight side: compare with the truth
    in post-processing).
    """

    count: int = static()
    phi: Any  # (6, 6)
    gamma: Any  # (6, 3) [s^2 ... ] input matrix of the acceleration
    qd: Any  # (6, 6) process noise per step
    r: Any  # (6, 6) measurement noise
    p0: Any  # (6, 6) initial covariance
    nominal_mass: Any  # (N,) [kg]

    navigation = True
    refresh_on_observe = True  # records: the estimate the law uses (after the update at t_k)

    def signals(self):
        return (
            Signal("navigation_estimate", STATE, "m, m s-1", "relative state estimate", "LVLH"),
            Signal(
                "navigation_sigma",
                ("component",),
                "m, m s-1",
                "the filter's standard deviation of each state component after the update",
            ),
        )

    def initial_state(self, measurement0):
        return NavigationState(jnp.asarray(measurement0), jnp.asarray(self.p0))

    def update(self, t, state: NavigationState, inputs: FlightInputs):
        x, p = state
        gain = jnp.linalg.solve((p + self.r).T, p.T).T  # K = P (P + R)^-1
        x = x + (inputs.measurement - x) @ gain.T
        eye = jnp.eye(6)
        p = (eye - gain) @ p @ (eye - gain).T + gain @ self.r @ gain.T  # Joseph form
        new = NavigationState(x, 0.5 * (p + p.T))
        return new, x

    def predict(self, t, state: NavigationState, command, dt):
        x, p = state
        accel = command / self.nominal_mass[:, None]
        x = x @ self.phi.T + accel @ self.gamma.T
        p = self.phi @ p @ self.phi.T + self.qd
        return NavigationState(x, 0.5 * (p + p.T))

    def current(self, state: NavigationState):
        return state.x_hat

    def outputs(self, t, state, estimate):
        return {
            "navigation_estimate": estimate,
            "navigation_sigma": jnp.sqrt(jnp.diagonal(state.p)),
        }
