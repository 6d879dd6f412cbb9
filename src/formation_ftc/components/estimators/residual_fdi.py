"""Estimator ``residual-fdi``: fault detection and isolation from relative-navigation residuals: a
residual generator (Kalman innovation or one-step parity relation) on the measured LVLH relative
states, a statistical test (CUSUM or a fixed threshold) per spacecraft and axis, and isolation to the
channel that crossed first.

Its on-board model is that of ``relative-navigation-filter`` (the same section fields, builder inputs
of ``phi``, ``gamma``, ``qd``, ``r``, and ``nominal_mass``). Needs the plant's ``translational-state``;
provides ``fault-alarm`` (its estimate reports ``detected``: the ``hierarchical`` supervisor can switch
on it) and ``fdi-records`` (``fdi_detected``, ``fdi_isolated``: what ``fdi-scores`` compares with the
true fault). With ``identification = "rls"`` it also identifies each channel's effectiveness and bias
(:func:`identify_channels`) and provides ``fault-identification``. ``formation-ftc check`` states the
residual model's assumption about the command and the stability of the navigation model.
"""

from __future__ import annotations

import math
from typing import Any, Literal, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from pydantic import Field, model_validator

from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.components.estimators._fdi import (
    FdiEstimator,
    FdiForgetting,
    FdiTestSection,
    detection_outputs,
    detection_signals,
    identification_outputs,
    identification_signals,
    identify_channels,
    latch_first_alarm,
    rls_prior,
    sequential_test,
)
from formation_ftc.components.estimators.relative_navigation_filter import (
    NAVIGATION_RECORDS,
    NAVIGATION_SIGNALS,
    RelativeNavigationSection,
    filter_model,
    innovation_nis,
    kalman_predict,
    kalman_update,
    navigation_conditions,
)
from formation_ftc.sim.components import FlightInputs, component, static
from formation_ftc.sim.contract import Condition, as_float

__all__ = [
    "ResidualFdi",
    "ResidualFdiSection",
    "FdiState",
    "sequential_test",
    "latch_first_alarm",
    "identify_channels",
    "rls_prior",
    "window_model",
    "isolated_effectiveness",
    "EFFECTIVENESS_MIN",
]

#: smallest identified effectiveness a reconfiguration uses (an outage identifies as about 0) [-]
EFFECTIVENESS_MIN = 0.05


def isolated_effectiveness(estimate) -> tuple[jax.Array, jax.Array]:
    """What a reconfiguration may use of an identifying FDI's estimate: ``(use, effectiveness)``, both
    (N, 3) -- ``use`` true on the channel isolated at the alarm once it is identified, and the
    identified effectiveness clipped to [:data:`EFFECTIVENESS_MIN`, 1] (a channel identified above 1 is
    taken as healthy).

    Parameters
    ----------
    estimate : mapping
        The estimate of :class:`ResidualFdi` with ``identification = "rls"`` (``detected``,
        ``isolated``, ``identified``, ``effectiveness``).

    Returns
    -------
    tuple of jax.Array
        ``(use, effectiveness)`` [-].

    Examples
    --------
    >>> import numpy as np
    >>> est = {"detected": np.asarray(True), "isolated": np.array([[False, True, False]]),
    ...        "identified": np.ones((1, 3), bool), "effectiveness": np.array([[0.8, 0.01, 1.2]])}
    >>> use, eff = isolated_effectiveness(est)
    >>> np.asarray(use).tolist(), np.asarray(eff).tolist()
    ([[False, True, False]], [[0.8, 0.05, 1.0]])
    """
    use = jnp.asarray(estimate["detected"]) & estimate["isolated"] & estimate["identified"]
    return use, jnp.clip(estimate["effectiveness"], EFFECTIVENESS_MIN, 1.0)


class FdiState(NamedTuple):
    x_hat: Any  # (N, 6) predicted state (Kalman residual)
    p: Any  # (6, 6) predicted covariance (Kalman residual)
    y_prev: Any  # (N, 6) previous measurement (parity residual)
    a_prev: Any  # (N, 3) previous commanded acceleration [m/s^2] (parity residual)
    started: Any  # () a previous sample exists (parity residual)
    tested: Any  # (N, 3) channels whose command stayed below the rated thrust over the last step
    g_pos: Any  # (N, 3) CUSUM statistic of a positive shift [-]
    g_neg: Any  # (N, 3) CUSUM statistic of a negative shift [-]
    detected: Any  # () latched alarm
    isolated: Any  # (N, 3) latched one-hot faulty channel
    theta: Any = None  # (N, 3, 2) [effectiveness - 1, bias] per channel (identification = "rls")
    theta_cov: Any = None  # (N, 3, 2, 2) their covariance
    win_pred: Any = None  # (N, 6) the window's start measurement propagated with the commands
    win_reg: Any = None  # (N, 3, 6) the state each channel's commands of the window moved
    win_tested: Any = None  # (N, 3) every step of the window tested the channel
    win_steps: Any = None  # () steps the window spans so far


@component
class ResidualFdi(FdiEstimator):
    """Detects and isolates a thruster fault (spacecraft i, axis j) from the velocity residuals.

    Residual ``e_k`` of the measured relative state ``y_k = q_k + v_k`` (N, 6), ``v_k ~ N(0, r)``, with
    the on-board model ``q_{k+1} = phi q_k + gamma f_k / m_nom + w_k`` (:mod:`formation_ftc.design.kalman`)::

        kalman:  e_k = y_k - q_hat_k^-                      S = P_k^- + r   (innovation; the filter's
                                                                            measurement update follows)
        parity:  e_k = y_k - phi y_{k-1} - gamma a_{k-1}     S = r + phi r phi^T + qd
                                                            (no state: exact for a full-state measurement)

    Each velocity component is standardised, ``z = e[:, 3 + j] / sqrt(S[3 + j, 3 + j])``, and tested per
    channel: ``cusum`` -- ``g+ = max(0, g+ + z - drift)``, ``g- = max(0, g- - z - drift)``, alarm when
    either exceeds ``threshold`` (Page's two-sided CUSUM); ``fixed`` -- alarm when ``|z| > threshold``.
    The first alarm is latched (``detected``) and isolates the channel with the largest statistic at
    that step (``isolated``, one-hot (N, 3)). A channel whose command reaches the stated rated thrust
    ``force_limit`` [N] is not tested on the residual spanning that step (a thrust limit may cut the
    force; the residual cannot tell it from a fault); with ``at_limit = "clip"`` the model applies
    ``clip(f_k, -force_limit, force_limit)`` instead (the force of a healthy rated thruster, per axis)
    and every channel stays tested, so a fault of a saturated thruster shows as well. A fault of the
    force shows in the velocity residual of its own spacecraft and axis first (the Coriolis coupling
    moves it to the other in-plane axis only over a fraction of an orbit), which is what isolation
    relies on. Pair ``skip`` with the memoryless parity residual: a Kalman prediction carries the
    unclipped command into the tested channels.

    Estimate (what a supervisor or a law may read): ``{"detected": (), "isolated": (N, 3),
    "statistic": (N, 3)}``. Records ``fdi_statistic``, ``fdi_detected`` and ``fdi_isolated``.

    Navigation (``fly_on_filter = True``, Kalman residual only): the estimate also carries the filter's
    state after the measurement update, ``"navigation"`` (N, 6), which the controller reads in place of
    the measurement: the loop flies on filtered navigation and is watched by the FDI at once. Records
    ``navigation_estimate`` and ``navigation_sigma`` as ``relative-navigation-filter`` does. With
    identification, the filter predicts the isolated channel with its identified effectiveness and
    bias, so that after a fault the navigation follows the faulty thruster instead of the model of a
    healthy one.

    Identification (``identification = "rls"``): every channel's effectiveness and bias by recursive
    least squares with forgetting on the parity residual's velocity part (:func:`identify_channels`;
    whatever ``residual`` the detection uses), from the prior effectiveness 1 +- 1 and bias 0 +-
    ``bias_prior_std``; the channel isolated at the first alarm starts again from that prior (its
    estimate is then the faulty actuator's, not an average with its healthy past). A channel is
    *identified* when the standard deviation of its effectiveness has
    fallen to ``identification_std``; before that its effectiveness is reported as NaN, not as a number
    (a channel whose command never varied cannot be identified). Adds ``"effectiveness"``,
    ``"effectiveness_std"``, ``"bias"`` (acceleration [m/s^2]) and ``"identified"`` (N, 3) to the
    estimate and records ``fdi_effectiveness`` (NaN where not identified) and
    ``fdi_effectiveness_std``. The residual model assumes a command held over the step, and channels
    the ``skip`` rule leaves untested are not updated either.
    """

    count: int = static()
    residual: str = static()
    test: str = static()
    phi: Any  # (6, 6)
    gamma: Any  # (6, 3)
    qd: Any  # (6, 6)
    r: Any  # (6, 6)
    parity_cov: Any  # (6, 6) covariance of the parity residual
    nominal_mass: Any  # (N,) [kg]
    drift: Any  # CUSUM drift [-]
    threshold: Any  # alarm threshold [-]
    force_limit: Any = float("inf")  # rated thrust per axis [N]
    at_limit: str = static(default="skip")  # "skip" or "clip" at force_limit (docstring)
    identification: str = static(default="off")  # "off" or "rls" (docstring)
    fly_on_filter: bool = static(default=False)  # the law flies on the Kalman estimate (docstring)
    forgetting: Any = 1.0  # RLS forgetting factor lambda [-]
    identification_std: Any = 0.05  # effectiveness std at which a channel counts as identified [-]
    bias_prior_std: Any = 1e-3  # prior standard deviation of a channel's bias [m/s^2]
    window_bias_gain: Any = None  # (3,) velocity a unit acceleration held over the window adds [s]
    window_noise: Any = None  # (3,) variance of the window residual's velocity components [(m/s)^2]
    window: int = static(default=1)  # steps of the identification window

    def needs(self) -> dict[str, str]:
        return {"translational-state": "form its residuals of the LVLH relative states"}

    def provides(self) -> frozenset[str]:
        navigation = {NAVIGATION_RECORDS} if self.fly_on_filter else set()
        return super().provides() | {"fault-alarm"} | navigation

    def conditions(self, loop) -> list[Condition]:
        """The residual model's assumption about the command, and the navigation model's stability."""
        sampled = bool(loop.controller.sampled)
        return [
            Condition(
                name="FDI: command held over each step",
                reference="docs/concepts/navigation-and-fdi.md",
                value=f"controller {type(loop.controller).__name__} "
                + ("is sampled" if sampled else "is evaluated inside the step"),
                requirement="a sampled law (the residual model holds the command over the step)",
                holds=sampled,
                required=False,
                basis="exact",
                detail=(
                    "exact: with a law evaluated at every integrator stage the command varies inside "
                    "the step, an input the residual does not model (measured on cw-fdi-thruster-bias "
                    "with the LQR continuous: 0.36 sigma per step during the acquisition, a false "
                    "alarm at 12 s)"
                ),
            ),
            *navigation_conditions(self.phi, self.qd, self.r)[:1],
        ]

    def signals(self):
        rls = self.identification == "rls"
        return (
            detection_signals("LVLH", "axis", "channel")
            + (identification_signals("LVLH", "channel") if rls else ())
            + (NAVIGATION_SIGNALS if self.fly_on_filter else ())
        )

    def initial_state(self, measurement0):
        y = jnp.asarray(measurement0)
        rls = self.identification == "rls"
        return FdiState(
            x_hat=y,
            p=jnp.asarray(self.r),
            y_prev=y,
            a_prev=jnp.zeros((self.count, 3)),
            started=jnp.asarray(False),
            tested=jnp.ones((self.count, 3), dtype=bool),
            **self._test_state(),
            **(dict(**self._window_start(y), win_steps=jnp.asarray(0)) if rls else {}),
        )

    def _window_start(self, y) -> dict[str, Any]:
        """An identification window that starts at the measurement ``y``."""
        return {
            "win_pred": y,
            "win_reg": jnp.zeros((self.count, 3, 6)),
            "win_tested": jnp.ones((self.count, 3), dtype=bool),
        }

    def _residual(self, state: FdiState, y):
        """(residual (N, 6), its covariance (6, 6), valid)."""
        if self.residual == "kalman":
            return y - state.x_hat, state.p + self.r, jnp.asarray(True)
        e = y - state.y_prev @ self.phi.T - state.a_prev @ self.gamma.T
        return e, self.parity_cov, state.started

    def update(self, t, state: FdiState, inputs: FlightInputs):
        y = inputs.measurement
        e, S, valid = self._residual(state, y)
        z = e[:, 3:] / jnp.sqrt(jnp.diagonal(S)[3:])  # standardised velocity residual (N, 3)
        z = jnp.where(valid & state.tested, z, 0.0)
        g_pos, g_neg, stat, alarm = self._test(state, z)
        detected, isolated, first = latch_first_alarm(stat, alarm, state.detected, state.isolated)
        x_hat, p = state.x_hat, state.p
        if self.residual == "kalman":  # the filter's measurement update
            x_hat, p = kalman_update(x_hat, p, y, self.r)
        new = state._replace(
            x_hat=x_hat,
            p=p,
            y_prev=y,
            started=jnp.asarray(True),
            g_pos=g_pos,
            g_neg=g_neg,
            detected=detected,
            isolated=isolated,
        )
        estimate = {"detected": new.detected, "isolated": isolated, "statistic": stat}
        if self.fly_on_filter:  # the law reads the filtered state in place of the measurement
            estimate["navigation"] = x_hat
            estimate["nis"] = innovation_nis(e, S)
        if self.identification == "rls":
            new, identified = self._identify(state, new, y, valid, first & isolated)
            estimate |= identified
        return new, estimate

    def _identify(self, state: FdiState, new: FdiState, y, valid, restart):
        """RLS of every channel's effectiveness and bias (``identify_channels``) on the parity residual
        of each completed window of ``window`` steps: the measurement now against the window's start
        measurement propagated with the commands. The channel isolated at the first alarm
        (``restart``) starts again from the prior, so that its estimate is that of the faulty
        actuator, not an average with its healthy past; the window starts again there too."""
        complete = state.win_steps == self.window
        parity = y - state.win_pred
        own = jnp.arange(3)  # each channel's own velocity component
        held = jnp.broadcast_to(self.window_bias_gain, (self.count, 3))
        regressor = jnp.stack([state.win_reg[:, own, 3 + own], held], axis=-1)
        theta_in, cov_in = self._restart(state.theta, state.theta_cov, restart)
        theta, cov = identify_channels(
            theta_in, cov_in, parity[:, 3:], regressor, self.window_noise, self.forgetting
        )
        use = (valid & complete & state.win_tested)[..., None]
        theta = jnp.where(use, theta, theta_in)
        cov = jnp.where(use[..., None], cov, cov_in)
        # forgetting without excitation inflates P past the prior (windup): no information is left
        # there, so the channel's covariance goes back to the prior
        cov0 = self._prior()[1]
        cov = jnp.where((cov[..., 0, 0] > cov0[..., 0, 0])[..., None, None], cov0, cov)
        std = jnp.sqrt(jnp.maximum(cov[..., 0, 0], 0.0))
        identified = std <= self.identification_std
        again = complete | ~valid | jnp.any(restart)  # a new window from this measurement
        window = {
            k: jnp.where(again, v, getattr(state, k)) for k, v in self._window_start(y).items()
        }
        steps = jnp.where(again, 0, state.win_steps)
        return new._replace(theta=theta, theta_cov=cov, win_steps=steps, **window), {
            "effectiveness": 1.0 + theta[..., 0],
            "effectiveness_std": std,
            "bias": theta[..., 1],
            "identified": identified,
        }

    def predict(self, t, state: FdiState, command, dt):
        if self.at_limit == "clip":  # the force a healthy rated thruster applies; all tested
            force = jnp.clip(command, -self.force_limit, self.force_limit)
            tested = jnp.ones_like(state.tested)
        else:
            force = command
            tested = jnp.abs(command) < self.force_limit
        accel = force / self.nominal_mass[:, None]
        x_hat, p = state.x_hat, state.p
        if self.residual == "kalman":
            x_hat, p = kalman_predict(
                x_hat, p, self._modelled(state, accel), self.phi, self.gamma, self.qd
            )
        state = state._replace(x_hat=x_hat, p=p, a_prev=accel, tested=tested)
        if self.identification == "rls":  # the identification window, with the commanded accel
            state = state._replace(
                win_pred=state.win_pred @ self.phi.T + accel @ self.gamma.T,
                win_reg=state.win_reg @ self.phi.T
                + accel[..., None] * jnp.swapaxes(self.gamma, 0, 1)[None],
                win_tested=state.win_tested & tested,
                win_steps=state.win_steps + 1,
            )
        return state

    def _modelled(self, state: FdiState, accel):
        """The acceleration the filter predicts with: the command, and, with identification, on the
        channel isolated at the alarm the identified actuator ``(1 + theta_0) a + theta_1`` (the
        posterior mean: shrunk toward the command while the estimate is uncertain), so that the
        navigation a law flies on follows the faulty thruster."""
        if self.identification != "rls":
            return accel
        faulty = state.detected & state.isolated
        identified = accel * (1.0 + state.theta[..., 0]) + state.theta[..., 1]
        return jnp.where(faulty, identified, accel)

    def outputs(self, t, state, estimate):
        out = detection_outputs(estimate["statistic"], estimate["detected"], estimate["isolated"])
        if self.fly_on_filter:
            out["navigation_estimate"] = estimate["navigation"]
            out["navigation_sigma"] = jnp.sqrt(jnp.diagonal(state.p))
            out["navigation_covariance"] = state.p
            out["navigation_nis"] = estimate["nis"]
        if self.identification == "rls":
            out |= identification_outputs(
                estimate["identified"], estimate["effectiveness"], estimate["effectiveness_std"]
            )
        return out


class ResidualFdiSection(RelativeNavigationSection, FdiTestSection):
    """Thruster-fault detection and isolation from the relative-state residuals."""

    residual: Literal["kalman", "parity"] = Field(
        "kalman",
        description="Residual generator: the Kalman innovation or the one-step parity relation.",
    )
    force_limit: float = Field(
        math.inf,
        gt=0,
        description=(
            "Rated thrust per axis [N] (flight knowledge): a channel whose command reaches it is not "
            "tested over that step (a thrust limit may cut the force, which the residual cannot tell "
            "from a fault); inf: every channel always tested. See at_limit."
        ),
    )
    at_limit: Literal["skip", "clip"] = Field(
        "skip",
        description=(
            "What the residual does at the rated thrust force_limit: skip -- a channel whose command "
            "reaches it is not tested over that step; clip -- the on-board model applies the command "
            "clipped to +-force_limit per axis (what a healthy rated thruster gives) and every channel "
            "is tested, so a fault of a saturated thruster shows too. clip needs a finite force_limit."
        ),
    )

    fly_on_filter: bool = Field(
        False,
        description="The law flies on the FDI's Kalman estimate (the filtered relative state) in place "
        "of the raw measurement, while the FDI watches the same filter's innovations (residual = "
        "'kalman' only) [-].",
    )
    forgetting: FdiForgetting = 0.9995
    bias_prior_std: float = Field(
        1e-3,
        gt=0,
        description="Prior standard deviation of a channel's bias acceleration [m/s^2].",
    )
    identification_window: float | None = builder_input(
        None,
        gt=0,
        description="Span of the parity residual the identification regresses [s] (rounded to whole "
        "steps; default one step). Over m steps the fault's velocity grows m-fold while the "
        "measurement noise at the window's ends does not: a longer window identifies a small "
        "command's fault sooner, as long as the on-board model holds over it.",
    )

    @model_validator(mode="after")
    def _combinations(self):
        if self.fly_on_filter and self.residual != "kalman":
            raise ValueError(
                'fly_on_filter = true: the law flies on the Kalman estimate; give residual = "kalman" '
                "(the parity residual keeps no state estimate)"
            )
        if self.at_limit == "clip" and not math.isfinite(self.force_limit):
            raise ValueError(
                'at_limit = "clip": give the rated thrust force_limit [N] (finite, > 0) to clip at'
            )
        return self


def window_model(phi, gamma, qd, r, steps: int) -> tuple[np.ndarray, np.ndarray]:
    """The velocity a unit acceleration held over ``steps`` steps adds per axis [s], and the variance of
    the window parity residual's velocity components ``r + phi^m r phi^m' + sum_i<m phi^i qd phi^i'``
    [(m/s)^2], of the on-board model ``(phi, gamma, qd, r)`` (:class:`ResidualFdi`'s identification).

    Parameters
    ----------
    phi, gamma : array_like, shape (6, 6), (6, 3)
        The one-step transition and input matrices of the relative state [SI].
    qd, r : array_like, shape (6, 6)
        Process noise per step and measurement noise covariances [SI].
    steps : int
        Steps m of the window, >= 1.

    Returns
    -------
    tuple of numpy.ndarray, shape (3,)
        The velocity gain of a held unit acceleration per axis [s] and the residual's velocity
        variance per axis [(m/s)^2].

    Examples
    --------
    >>> import numpy as np
    >>> phi = np.eye(6); phi[:3, 3:] = np.eye(3)  # a double integrator at dt = 1 s
    >>> gamma = np.vstack([0.5 * np.eye(3), np.eye(3)])
    >>> gain, noise = window_model(phi, gamma, np.zeros((6, 6)), np.eye(6) * 1e-6, 10)
    >>> gain.tolist(), noise.tolist()
    ([10.0, 10.0, 10.0], [2e-06, 2e-06, 2e-06])
    """
    phi, gamma, qd, r = (np.asarray(x, dtype=float) for x in (phi, gamma, qd, r))
    power, held, noise = np.eye(6), np.zeros((6, 3)), np.asarray(r, dtype=float).copy()
    for _ in range(steps):
        held += power @ gamma
        noise += power @ qd @ power.T
        power = phi @ power
    noise += power @ r @ power.T
    return np.diagonal(held[3:, :]).copy(), np.diagonal(noise)[3:].copy()


def _build(sec: ResidualFdiSection, ctx: BuildContext) -> ResidualFdi:
    """The FDI of a validated ``[estimator] type = "residual-fdi"`` section."""
    a = filter_model(sec, ctx)
    window = sec.identification_window
    steps = 1 if window is None else max(1, int(round(window / ctx.dt)))
    gain, noise = window_model(a["phi"], a["gamma"], a["qd"], a["r"], steps)
    return ResidualFdi(
        count=ctx.count,
        **sec.model_dump(include={"residual", "at_limit", "fly_on_filter"}),
        **sec.fdi_fields(),
        parity_cov=as_float(a["r"] + a["phi"] @ a["r"] @ a["phi"].T + a["qd"]),
        force_limit=as_float(sec.force_limit),
        window_bias_gain=as_float(gain),
        window_noise=as_float(noise),
        window=steps,
        **a,
    )


register(
    "estimator",
    "residual-fdi",
    ResidualFdiSection,
    _build,
    "thruster-fault detection and isolation: Kalman or parity residual, CUSUM or fixed threshold",
)
