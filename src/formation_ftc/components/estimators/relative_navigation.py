"""A relative navigation filter: a linear Kalman filter on the measured LVLH relative states."""

from __future__ import annotations

from typing import Any, NamedTuple

import jax.numpy as jnp

from formation_ftc.sim.components import Estimator, FlightInputs, Signal, component, static

__all__ = ["RelativeNavigationFilter", "NavigationState", "kalman_update", "kalman_predict"]

STATE = ("spacecraft", "component")


def kalman_update(x, p, y, r):
    """Measurement update of a full-state measurement ``y = x + v``, ``v ~ N(0, r)`` (Joseph form).

    Parameters
    ----------
    x : array, shape (N, 6)
        Predicted states (one row per spacecraft) [m, m/s].
    p : array, shape (6, 6)
        Their common predicted covariance.
    y : array, shape (N, 6)
        Measurements [m, m/s].
    r : array, shape (6, 6)
        Measurement-noise covariance.

    Returns
    -------
    tuple of array
        ``x + (y - x) K^T`` and ``(I - K) P (I - K)^T + K r K^T`` with ``K = P (P + r)^-1``.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> x, p = kalman_update(jnp.zeros((1, 6)), jnp.eye(6), jnp.ones((1, 6)), jnp.eye(6))
    >>> float(x[0, 0]), float(p[0, 0])  # equal confidence: halfway, half the variance
    (0.5, 0.5)
    """
    gain = jnp.linalg.solve((p + r).T, p.T).T
    eye = jnp.eye(p.shape[0])
    p = (eye - gain) @ p @ (eye - gain).T + gain @ r @ gain.T
    return x + (y - x) @ gain.T, 0.5 * (p + p.T)


def kalman_predict(x, p, accel, phi, gamma, qd):
    """Time update over one step with the acceleration held.

    Parameters
    ----------
    x : array, shape (N, 6)
        States after the update [m, m/s].
    p : array, shape (6, 6)
        Their common covariance.
    accel : array, shape (N, 3)
        Acceleration held over the step [m/s^2].
    phi, gamma, qd : array
        The discrete model (:func:`formation_ftc.design.kalman.discrete_model`).

    Returns
    -------
    tuple of array
        ``x phi^T + accel gamma^T`` and ``phi P phi^T + qd``.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> x, p = kalman_predict(jnp.ones((1, 6)), jnp.eye(6), jnp.zeros((1, 3)), jnp.eye(6),
    ...                       jnp.zeros((6, 3)), jnp.eye(6))
    >>> float(x[0, 0]), float(p[0, 0])
    (1.0, 2.0)
    """
    p = phi @ p @ phi.T + qd
    return x @ phi.T + accel @ gamma.T, 0.5 * (p + p.T)


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
        x, p = kalman_update(state.x_hat, state.p, inputs.measurement, self.r)
        return NavigationState(x, p), x

    def predict(self, t, state: NavigationState, command, dt):
        accel = command / self.nominal_mass[:, None]
        return NavigationState(
            *kalman_predict(state.x_hat, state.p, accel, self.phi, self.gamma, self.qd)
        )

    def outputs(self, t, state, estimate):
        return {
            "navigation_estimate": estimate,
            "navigation_sigma": jnp.sqrt(jnp.diagonal(state.p)),
        }
