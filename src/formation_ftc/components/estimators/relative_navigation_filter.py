"""Estimator ``relative-navigation-filter``: a linear Kalman filter on the measured LVLH relative
states; the controller flies on its estimate instead of the raw measurement.

The filter uses the on-board Clohessy-Wiltshire model of a stated circular orbit (design in
:mod:`formation_ftc.design.kalman`). Every number of the filter is flight knowledge and is stated in
the section: the orbit, the assumed measurement noise and acceleration noise (builder inputs of the
discrete model ``phi``, ``gamma``, ``qd``, ``r``) and the nominal masses (``nominal_mass``, default
100 kg). Needs the plant's ``translational-state``. ``formation-ftc check`` states the steady-state
filter's stability and standard deviations (:func:`navigation_conditions`).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import jax.numpy as jnp
import numpy as np
from pydantic import Field

from formation_ftc.components._flight_defaults import NOMINAL_MASS
from formation_ftc.components._registry import BuildContext, builder_input, per_spacecraft, register
from formation_ftc.components._sections import Masses, section_floats
from formation_ftc.components.estimators._acceleration_model import WrapsInner
from formation_ftc.config.base import StrictModel
from formation_ftc.core.constants import MU_EARTH
from formation_ftc.sim.components import Estimator, FlightInputs, Signal, component, static
from formation_ftc.sim.contract import STATE, Condition, as_float

__all__ = [
    "RelativeNavigationFilter",
    "RelativeNavigationSection",
    "NavigationState",
    "kalman_update",
    "kalman_predict",
    "navigation_conditions",
    "filter_model",
    "innovation_nis",
    "NAVIGATION_RECORDS",
    "FilteredEstimator",
    "filtered",
]

#: the capability of an estimator whose law flies on its filter and that records the filter's estimate,
#: covariance and normalised innovation squared (the ``navigation-consistency`` evaluation scores them)
NAVIGATION_RECORDS = "navigation-records"


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


def innovation_nis(innovation, s):
    """Normalised innovation squared of every spacecraft: ``e_i^T S^-1 e_i`` [-] (chi-square with 6
    degrees of freedom for a consistent filter).

    Parameters
    ----------
    innovation : array, shape (N, 6)
        Measurement minus predicted state [m, m/s].
    s : array, shape (6, 6)
        Its covariance ``P_pred + R``.

    Returns
    -------
    array, shape (N,)

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> float(innovation_nis(jnp.ones((1, 6)), 2.0 * jnp.eye(6))[0])
    3.0
    """
    return jnp.einsum("ni,ni->n", innovation, jnp.linalg.solve(s, innovation.T).T)


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


#: what a filter that navigates records (``relative-navigation-filter``, ``residual-fdi`` navigating)
NAVIGATION_SIGNALS = (
    Signal("navigation_estimate", STATE, "m, m s-1", "relative state estimate", "LVLH"),
    Signal(
        "navigation_sigma",
        ("component",),
        "m, m s-1",
        "the filter's standard deviation of each state component after the update",
    ),
    Signal(
        "navigation_covariance",
        ("component", "component_2"),
        "m2, m2 s-1, m2 s-2",
        "the filter's error covariance after the update (one for every spacecraft)",
    ),
    Signal(
        "navigation_nis",
        ("spacecraft",),
        "1",
        "normalised innovation squared of the update (chi-square, 6 degrees of freedom)",
    ),
)


class NavigationState(NamedTuple):
    x_hat: Any  # (N, 6) estimate [m, m/s]
    p: Any  # (6, 6) error covariance (one model and one noise for every spacecraft)
    nis: Any  # (N,) normalised innovation squared of the last update [-]


@component
class RelativeNavigationFilter(Estimator):
    """Kalman filter of every spacecraft's relative state ``q = [rho, rho']`` (LVLH) from the sensors'
    noisy measurement ``y_k = q_k + v_k``, ``v_k ~ N(0, r)``, with the on-board linear model
    (:func:`formation_ftc.design.kalman.discrete_model`)::

        q_{k+1} = phi q_k + gamma f_k / m_nom + w_k,   w_k ~ N(0, qd)

    driven by the controller's command ``f_k`` [N] held over the step, clipped to the stated rated
    thrust ``force_limit`` per axis (what a healthy rated thruster applies; inf: no limit), per unit of
    the stated nominal mass ``nominal_mass`` (N,) [kg]. At every step: measurement update at t_k (Joseph form), then, after
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
    force_limit: Any = float("inf")  # rated thrust per axis [N]

    navigation = True

    def needs(self) -> dict[str, str]:
        return {"translational-state": "estimate the LVLH relative states"}

    def provides(self) -> frozenset[str]:
        return frozenset({NAVIGATION_RECORDS})

    def conditions(self, loop) -> list[Condition]:
        return navigation_conditions(self.phi, self.qd, self.r)

    def signals(self):
        return NAVIGATION_SIGNALS

    def initial_state(self, measurement0):
        y = jnp.asarray(measurement0)
        return NavigationState(y, jnp.asarray(self.p0), jnp.zeros(y.shape[0]))

    def update(self, t, state: NavigationState, inputs: FlightInputs):
        y = inputs.measurement
        nis = innovation_nis(y - state.x_hat, state.p + self.r)
        x, p = kalman_update(state.x_hat, state.p, y, self.r)
        return NavigationState(x, p, nis), x

    def predict(self, t, state: NavigationState, command, dt):
        force = jnp.clip(command, -self.force_limit, self.force_limit)
        accel = force / self.nominal_mass[:, None]
        x, p = kalman_predict(state.x_hat, state.p, accel, self.phi, self.gamma, self.qd)
        return NavigationState(x, p, state.nis)

    def outputs(self, t, state, estimate):
        return {
            "navigation_estimate": estimate,
            "navigation_sigma": jnp.sqrt(jnp.diagonal(state.p)),
            "navigation_covariance": state.p,
            "navigation_nis": state.nis,
        }


@component
class FilteredEstimator(WrapsInner):
    """Another estimator (``inner``, e.g. the iterative learning observer) run on this filter's
    estimate in place of the raw measurement, while the law flies on the same estimate: at t_k the
    filter's measurement update, then ``inner``'s update with ``y_k := x_hat_k``; after the control
    step both time updates with the command. The estimate is ``inner``'s (a mapping) with the filter's
    under :data:`~formation_ftc.sim.loop.NAVIGATION_ESTIMATE` (the loop gives the law that entry in
    place of the measurement); both record their signals. Needs and provides what both do."""

    navigation_filter: RelativeNavigationFilter
    inner: Estimator

    def initial_state(self, measurement0):
        return {
            "navigation": self.navigation_filter.initial_state(measurement0),
            "inner": self.inner.initial_state(measurement0),
        }

    def update(self, t, state, inputs: FlightInputs):
        from formation_ftc.sim.loop import NAVIGATION_ESTIMATE

        nav, x_hat = self.navigation_filter.update(t, state["navigation"], inputs)
        inner, est = self.inner.update(t, state["inner"], inputs._replace(measurement=x_hat))
        return {"navigation": nav, "inner": inner}, {**est, NAVIGATION_ESTIMATE: x_hat}

    def predict(self, t, state, command, dt):
        return {
            "navigation": self.navigation_filter.predict(t, state["navigation"], command, dt),
            "inner": self.inner.predict(t, state["inner"], command, dt),
        }

    def signals(self):
        return self.navigation_filter.signals() + self.inner.signals()

    def outputs(self, t, state, estimate):
        from formation_ftc.sim.loop import NAVIGATION_ESTIMATE

        nav = self.navigation_filter.outputs(t, state["navigation"], estimate[NAVIGATION_ESTIMATE])
        return nav | self.inner.outputs(t, state["inner"], estimate)

    def conditions(self, loop) -> list[Condition]:
        return self.navigation_filter.conditions(loop) + super().conditions(loop)

    def needs(self) -> dict[str, str]:
        return self.inner.needs() | self.navigation_filter.needs()

    def provides(self) -> frozenset[str]:
        return self.inner.provides() | self.navigation_filter.provides()


def filtered(
    inner: Estimator, sec: RelativeNavigationSection | None, ctx: BuildContext, mass: Any
) -> Estimator:
    """``inner`` as it is (``sec`` None), else run on the filter of ``sec`` (:class:`FilteredEstimator`).

    Parameters
    ----------
    inner : Estimator
        The estimator that reads the filter's estimate as its measurement.
    sec : RelativeNavigationSection or None
        The filter's section (an estimator's ``navigation`` table), or None.
    ctx : BuildContext
        The build's context (step, spacecraft count and the plant, which must be force-driven).
    mass : array_like
        The flight masses [kg] the filter uses where its section states none (those of ``inner``).

    Returns
    -------
    Estimator
        ``inner`` or the chain.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> sec = RelativeNavigationSection(semi_major_axis=7e6, position_noise_std=0.1,
    ...                                 velocity_noise_std=1e-3)
    >>> ctx = SimpleNamespace(dt=1.0, count=2, plant=SimpleNamespace(quantity="force"))
    >>> chain = filtered(Estimator(), sec, ctx, [100.0, 120.0])
    >>> chain.navigation_filter.nominal_mass.tolist(), sorted(chain.provides())
    ([100.0, 120.0], ['navigation-records'])
    """
    if sec is None:
        return inner
    if ctx.plant.quantity != "force":
        raise ValueError(
            "estimator.navigation: the navigation filter predicts with a force command per unit "
            f"nominal mass; this plant is driven by {ctx.plant.quantity} (give a force-driven plant "
            "or no navigation table)"
        )
    if "nominal_mass" not in sec.model_fields_set:
        sec = sec.model_copy(update={"nominal_mass": np.asarray(mass, float).tolist()})
    return FilteredEstimator(
        navigation_filter=_build(sec, ctx, "estimator.navigation"), inner=inner
    )


def navigation_conditions(phi, qd, r) -> list[Condition]:
    """The steady-state filter of the model ``(phi, qd, r)``: the stability of its error dynamics (with
    the Riccati residual) and the steady-state position and velocity standard deviations it promises.

    Parameters
    ----------
    phi, qd, r : array_like, shape (6, 6)
        Transition, process-noise and measurement-noise matrices of the on-board model.

    Returns
    -------
    list of Condition
        The stability condition (required) and the standard deviations (informative).

    Examples
    --------
    >>> import numpy as np
    >>> phi = np.eye(6) + np.diag(np.ones(3), 3)  # a double integrator over 1 s
    >>> stable, _ = navigation_conditions(phi, 1e-4 * np.eye(6), 1e-2 * np.eye(6))
    >>> stable.holds
    True
    """
    from formation_ftc.design.kalman import dare_relative_residual, steady_state_kalman

    phi, qd, r = (np.asarray(a, float) for a in (phi, qd, r))
    P, K = steady_state_kalman(phi, qd, r)
    residual = dare_relative_residual(P, phi, qd, r)
    posterior = (np.eye(6) - K) @ P
    rho = float(np.max(np.abs(np.linalg.eigvals(phi @ (np.eye(6) - K)))))
    sig = np.sqrt(np.diag(posterior))
    return [
        Condition(
            name="navigation filter: steady-state error dynamics stable",
            reference="design/kalman.py",
            value=f"spectral radius of phi (I - K) = {rho:.6f} (Riccati residual {residual:.1e})",
            requirement="< 1",
            holds=rho < 1.0 - 1e-9 and residual < 1e-8,
            required=True,
            basis="exact",
            detail=(
                "exact: eigenvalues of the estimation-error transition of the steady-state filter, "
                "with the discrete Riccati equation solved to the stated residual"
            ),
        ),
        Condition(
            name="navigation filter: steady-state standard deviation",
            reference="design/kalman.py",
            value=(
                f"position {np.max(sig[:3]):.3g} m, velocity {np.max(sig[3:]):.3g} m/s "
                f"(measurement {math.sqrt(r[0, 0]):g} m, {math.sqrt(r[3, 3]):g} m/s)"
            ),
            requirement="informative",
            holds=True,
            required=False,
            basis="informative",
            detail="informative: after the measurement update, from the model the filter states",
        ),
    ]


class RelativeNavigationSection(StrictModel):
    """Kalman filter of the LVLH relative states (on-board CW model of a circular orbit)."""

    semi_major_axis: float = builder_input(
        gt=0, description="Radius of the on-board circular reference orbit [m]."
    )
    mu: float = builder_input(MU_EARTH, gt=0, description="Gravitational parameter [m^3/s^2].")
    position_noise_std: float = builder_input(
        gt=0, description="Assumed std of the position measurement noise [m]."
    )
    velocity_noise_std: float = builder_input(
        gt=0, description="Assumed std of the velocity measurement noise [m/s]."
    )
    acceleration_noise_psd: float = builder_input(
        1e-10,
        ge=0,
        description=(
            "Spectral density of the unmodelled acceleration per axis [(m/s^2)^2/Hz] (J2, drag, "
            "model error, faults the filter does not know)."
        ),
    )
    force_limit: float = Field(
        math.inf,
        gt=0,
        description="Rated thrust per axis [N] (flight knowledge): the filter predicts with the "
        "command clipped to it, the force a healthy rated thruster applies; inf: no limit.",
    )
    nominal_mass: Masses = Field(
        NOMINAL_MASS,
        description="On-board mass per spacecraft that turns the commanded force into acceleration "
        "[kg], one or per spacecraft, > 0 (default 100 kg, a stated nominal value: never the "
        "plant's true masses).",
    )

    def model(self, dt: float):
        """(discrete model, R) of the filter at step ``dt`` [s]."""
        from formation_ftc.core.dynamics.cw import cw_matrices
        from formation_ftc.design.kalman import discrete_model

        n = math.sqrt(self.mu / self.semi_major_axis**3)
        A, B = cw_matrices(n)
        model = discrete_model(A, B, B, self.acceleration_noise_psd, dt)
        R = np.diag([self.position_noise_std**2] * 3 + [self.velocity_noise_std**2] * 3)
        return model, R


def filter_model(
    sec: RelativeNavigationSection, ctx: BuildContext, where: str = "estimator"
) -> dict[str, Any]:
    """The on-board model's arrays (``phi``, ``gamma``, ``qd``, ``r``, ``nominal_mass``) of a filter
    section at the scenario's step.

    Parameters
    ----------
    sec : RelativeNavigationSection
        The section (or one that extends it).
    ctx : BuildContext
        The build context (step and spacecraft count).
    where : str, optional
        The section's dotted name, for the errors.

    Returns
    -------
    dict of numpy.ndarray
        The component's model arrays.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> sec = RelativeNavigationSection(semi_major_axis=7e6, position_noise_std=0.1,
    ...                                 velocity_noise_std=1e-3)
    >>> arrays = filter_model(sec, SimpleNamespace(dt=1.0, count=2))
    >>> arrays["phi"].shape, arrays["nominal_mass"].tolist()
    ((6, 6), [100.0, 100.0])
    """
    model, R = sec.model(ctx.dt)
    mass = per_spacecraft(sec.nominal_mass, ctx.count, f"{where}.nominal_mass")
    return dict(
        **section_floats(model, "phi", "gamma", "qd"),
        r=as_float(R),
        nominal_mass=as_float(mass),
    )


def _build(
    sec: RelativeNavigationSection, ctx: BuildContext, where: str = "estimator"
) -> RelativeNavigationFilter:
    """The filter of a validated ``[estimator] type = "relative-navigation-filter"`` section (or of
    the table ``where``)."""
    arrays = filter_model(sec, ctx, where)
    return RelativeNavigationFilter(
        count=ctx.count, p0=arrays["r"], force_limit=as_float(sec.force_limit), **arrays
    )


register(
    "estimator",
    "relative-navigation-filter",
    RelativeNavigationSection,
    _build,
    "Kalman filter of the LVLH relative states; the controller reads its estimate instead of the "
    "measurement",
)
