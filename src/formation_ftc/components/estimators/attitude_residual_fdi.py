"""Estimator ``attitude-residual-fdi``: attitude fault detection, isolation and identification from the
rigid-body (Euler-Lagrange) residual, feeding the reconfiguration of the networked Euler-Lagrange law
(:mod:`formation_ftc.components.controllers.networked_el_hinf`) with detected -- not scripted, not
true -- information.

The residual is the body torque the model does not explain over one step: what the body torques
applied minus what was commanded. It lives in body axes, where the actuator's faults act (after the
Euler-angle allocation). Its test and first-alarm latch are those of the translational residual FDI
(:func:`~formation_ftc.components.estimators._fdi.sequential_test`,
:func:`~formation_ftc.components.estimators._fdi.latch_first_alarm`).

It reports to the Euler-angle law as the scripted FDI does: the flag of a generalised channel and u*.
The ``fdi-scores`` evaluation scores it against the fault-battery actuator's true fault (body axes).
Every number is flight knowledge stated in the section: the nominal inertia, the reference orbit, the
rated torque and the model-error level. Needs the capabilities ``euler-angle-measurement`` (3-2-1
Euler angles and body rates) and ``euler-angle-law`` (a law commanding the generalised torque).
The check of the command model against the law's sampling is a condition registered by the Mehrabian
package (:mod:`formation_ftc.papers.mehrabian.conditions`).
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal, NamedTuple

import jax.numpy as jnp
import numpy as np
from pydantic import Field

from formation_ftc.components._flight_defaults import MEHRABIAN_NOMINAL_INERTIA
from formation_ftc.components._registry import BuildContext, builder_input, per_spacecraft, register
from formation_ftc.components._sections import Inertia, positive_values, section_floats
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
)
from formation_ftc.core.constants import MU_EARTH
from formation_ftc.core.dynamics.euler_lagrange import generalized_to_body_torque, rbar_inv
from formation_ftc.core.euler_quaternion import dcm_from_euler_zyx
from formation_ftc.sim.components import FlightInputs, Signal, component, static
from formation_ftc.sim.contract import VEC, as_float

__all__ = [
    "AttitudeResidualFdi",
    "AttitudeFdiState",
    "AttitudeFdiEstimate",
    "rigid_body_residual",
    "AttitudeResidualFdiSection",
]


class AttitudeFdiState(NamedTuple):
    q_prev: Any  # (N, 3) measured 3-2-1 Euler angles at t_k [rad]
    w_prev: Any  # (N, 3) measured body rate at t_k [rad/s]
    tau_prev: Any  # (N, 3) nominal mean body torque over [t_k, t_k+1) [N m]
    tau_last: Any  # (N, 3) nominal body torque at the last command [N m]
    commanded: Any  # () a previous command exists
    valid: Any  # () tau_prev models the step just flown (a residual can be formed)
    tested: Any  # (N, 3) channels whose nominal torque stayed below the rated limit over the step
    g_pos: Any  # (N, 3) CUSUM statistic of a positive shift [-]
    g_neg: Any  # (N, 3) CUSUM statistic of a negative shift [-]
    f_hat: Any  # (N, 3) moving average of the residual, body axes [N m]
    residual: Any  # (N, 3) last residual, body axes [N m]
    detected: Any  # () latched alarm
    isolated: Any  # (N, 3) latched one-hot faulty (spacecraft, body axis)
    flag: Any  # (N, 3) latched one-hot generalised channel (spacecraft, Euler angle) of the law
    theta: Any = None  # (N, 3, 2) [effectiveness - 1, bias [N m]] per body channel (identification)
    theta_cov: Any = None  # (N, 3, 2, 2) their covariance


class AttitudeFdiEstimate(NamedTuple):
    """What the FDI hands on: ``flag`` and ``estimate`` (u*) as the law reads them (the fields of
    :class:`~formation_ftc.components.estimators.scripted_fdi.FDIOutput`, in the law's generalised channels), and the detection
    in body axes."""

    flag: Any  # (N, 3) 1.0 on the generalised channel to reconfigure [-]
    estimate: Any  # (N, 3) u*: identified fault as a generalised torque on that channel [N m]
    detected: Any  # () latched alarm
    isolated: Any  # (N, 3) latched one-hot (spacecraft, body axis)
    statistic: Any  # (N, 3) test statistic [-]
    residual: Any  # (N, 3) residual, body axes [N m]
    identified: Any  # (N, 3) moving average of the residual, body axes [N m]
    effectiveness: Any = None  # (N, 3) identified effectiveness, body axes (identification "rls")
    effectiveness_std: Any = None  # (N, 3) its standard deviation
    known: Any = None  # (N, 3) the effectiveness is identified (std <= identification_std)


def _omega(q, w, n):
    """Inertial body rate from the measured rate relative to the reference frame: ``w + n o_b`` with
    ``o_b`` the orbit normal (reference z axis) in body axes (third row of C(q))."""
    return w + n * dcm_from_euler_zyx(q)[..., 2, :]


def _gravity_gradient(q, J, n):
    """``3 n^2 r_b x (J r_b)``, ``r_b`` the radial unit (reference x axis) in body axes [N m]."""
    r_b = dcm_from_euler_zyx(q)[..., 0, :]
    return 3.0 * n**2 * jnp.cross(r_b, jnp.einsum("...ij,...j->...i", J, r_b))


def rigid_body_residual(q0, w0, q1, w1, tau, J, dt, n=0.0):
    """One-step parity residual of rigid bodies [N m, body axes] (the module's model, trapezoidal
    nonlinear terms)::

        omega = w + n o_b(q)                         (inertial rate; n = 0: w is inertial)
        r = J (omega_1 - omega_0) / dt + mean_{0,1}(omega x J omega - tau_gg(q)) - tau

    Parameters
    ----------
    q0, q1 : array_like, shape (N, 3)
        3-2-1 Euler angles [theta, phi, psi] relative to the reference frame at t_k, t_k+1 [rad].
    w0, w1 : array_like, shape (N, 3)
        Body rates relative to the reference frame at t_k, t_k+1, body axes [rad/s].
    tau : array_like, shape (N, 3)
        Body torque commanded over the step [N m].
    J : array_like, shape (N, 3, 3)
        Nominal inertia [kg m^2].
    dt : float
        Step [s].
    n : float
        Rotation rate of the reference frame (LVLH of a circular orbit: the orbit rate; gravity
        gradient included) [rad/s]; 0: an inertial reference, no gravity gradient.

    Returns
    -------
    jax.Array, shape (N, 3)
        The residual [N m]: the applied-minus-commanded torque up to the model's error.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.estimators.attitude_residual_fdi import rigid_body_residual
    >>> J = np.diag([20.0, 25.0, 30.0])[None]
    >>> z = np.zeros((1, 3))
    >>> w1 = np.array([[0.0, 0.5 * 0.1 / 25.0, 0.0]])  # 0.5 N m about y for 0.1 s, from rest
    >>> np.round(np.asarray(rigid_body_residual(z, z, z, w1, z, J, 0.1)), 12)
    array([[0. , 0.5, 0. ]])
    """

    def nonlinear(q, w):
        om = _omega(q, w, n)
        h = jnp.einsum("...ij,...j->...i", J, om)
        return om, jnp.cross(om, h) - _gravity_gradient(q, J, n)

    om0, c0 = nonlinear(q0, w0)
    om1, c1 = nonlinear(q1, w1)
    return jnp.einsum("...ij,...j->...i", J, om1 - om0) / dt + 0.5 * (c0 + c1) - tau


@component
class AttitudeResidualFdi(FdiEstimator):
    """Detects, isolates and identifies an actuator fault (spacecraft i, body axis k) of Euler-angle
    attitude laws from the rigid-body residual, and reports it in the law's generalised channels.

    Measurement: ``{"q": (N, 3) 3-2-1 Euler angles [rad], "w": (N, 3) body rates [rad/s]}`` relative to
    the reference frame (the ``quaternion-euler`` sensors). Command: the law's generalised torque
    ``tau_gen`` [N m], mapped to the nominal body torque ``tau_k = R_bar(q_k)^T tau_gen_k`` (the
    allocation). Its mean over the step is ``tau_k`` (``command = "held"``: a sampled law) or
    ``1.5 tau_k - 0.5 tau_k-1`` (``"extrapolated"``: a law evaluated inside the step, as
    ``networked-el-hinf`` is; the linear extrapolation to the step's midpoint removes the first-order
    error of holding a varying command; the first step is not tested). A channel whose nominal torque
    reaches the rated per-axis limit ``torque_limit`` at t_k, or by the step's end (extrapolated), is not
    tested over that step: a limit may cut its torque, which the residual cannot tell from a fault
    (whether the actuator has one is not flight knowledge here; a league level sets it).

    Residual (:func:`rigid_body_residual`) at t_k+1 from the samples at t_k and t_k+1, nominal inertia
    ``nominal_inertia``, standardised by the stated model-error level ``residual_std`` [N m]: ``z = r /
    residual_std``; then the test per (spacecraft, body axis) -- ``cusum`` or ``fixed`` as in
    :class:`~formation_ftc.components.estimators.residual_fdi.ResidualFdi` -- and the first alarm
    latched, isolating the body axis with the largest statistic.

    Identification: ``f_hat`` an exponential moving average of the residual (time constant
    ``identification_time``) over every step, tested or not: after a fault the residual is the fault's
    body torque ``f`` (applied minus commanded, whatever the law commands; a torque a limit cuts biases
    it, while the law reacting to the fault may command more than the rated torque). Report in the law's channels (its u_bar enters as
    ``tau_body = R_bar^T (tau_gen + u_bar)``, so a body fault ``f`` is ``u_bar = R_bar^{-T} f = W^T f``)::

        flag_{i,p} = 1 for p = argmax_p |W(q_alarm)_{k,p}| (latched at the alarm; at LVLH alignment
                     body x -> phi (roll), y -> theta (pitch), z -> psi (yaw))
        u*_{i,p}   = flag_{i,p} (W(q)^T (isolated * f_hat))_{i,p}       [N m]

    With ``identification = "rls"`` each body channel's effectiveness and bias are identified from the
    same residual, which after a fault is ``f = (effectiveness - 1) tau + bias`` for the step's mean
    nominal torque ``tau``: recursive least squares with forgetting (the translational FDI's
    :func:`~formation_ftc.components.estimators._fdi.identify_channels`) on the regressor
    ``[tau, 1]`` with noise standard deviation ``identification_noise_std`` (default ``residual_std``),
    over the tested steps; the effectiveness may also drift as a random walk (``effectiveness_walk``
    [1/sqrt(s)]; the bias has none: a walk of the bias as large as the excitation's effect would hide
    the effectiveness), which bounds how certain the estimate gets
    after a rich acquisition so that a later fault is followed within seconds, not after forgetting
    has worn that certainty off. A channel counts as
    identified once its effectiveness's standard deviation is at most ``identification_std``; a channel
    whose torque never varies is not (a held torque and a bias cannot be told apart): NaN is recorded
    there, no number. A loss of effectiveness on a settled hold changes the torque by almost nothing,
    below any mean-shift test; an identified effectiveness below ``1 - effectiveness_alarm`` by two of
    its standard deviations raises the alarm too (one-sided: the faults it is for lose effectiveness;
    the estimate's error is not white -- the model error over a smooth acquisition trades against the
    bias -- so the margin; the channel isolated is that with the largest of the CUSUM statistic over its
    threshold and ``(1 - effectiveness - 2 std) / effectiveness_alarm``), so that the reconfiguration engages on
    it with u* from the moving average as above (the fault torque measured; a u* modelled as
    ``(effectiveness - 1) tau`` from the law's own command closes an algebraic loop through the
    compensation that diverges for an effectiveness near 0, a stuck or failed wheel). The isolated
    channel's estimate starts again from the prior at the alarm. On a hold the channel must be
    excited to be identified: the law's stated excitation (``networked-el-hinf``
    ``excitation_amplitude``) is part of the command the residual's model knows.

    Records ``fdi_residual``, ``fdi_statistic``, ``fdi_detected``, ``fdi_isolated`` (body axes: what
    ``fdi-scores`` compares with the fault-battery's ``fault_channel``), ``fdi_flag`` and
    ``fdi_estimate`` (the law's channels, as the scripted FDI records them); with identification
    ``fdi_effectiveness`` (NaN: not identified) and ``fdi_effectiveness_std`` (body axes).
    """

    count: int = static()
    test: str = static()
    nominal_inertia: Any  # (N, 3, 3) nominal inertia [kg m^2]
    orbit_rate: Any  # () rotation rate of the reference frame [rad/s]
    torque_limit: Any  # (N, 1) rated per-axis torque: not tested at or above it [N m] (inf: none)
    residual_std: Any  # () [N m]
    drift: Any  # CUSUM drift [-]
    threshold: Any  # alarm threshold [-]
    smoothing: Any  # () EMA weight 1 - exp(-dt / identification_time) [-]
    command: str = static(default="held")  # "held" or "extrapolated"
    identification: str = static(default="off")  # "off" or "rls"
    forgetting: Any = 1.0  # RLS forgetting factor lambda [-]
    identification_std: Any = 0.05  # effectiveness std at which a channel counts as identified [-]
    bias_prior_std: Any = 0.01  # prior standard deviation of a channel's bias torque [N m]
    identification_noise: Any = 1e-3  # () residual noise the identification assumes [N m]
    walk: Any = 0.0  # (2, 2) random-walk covariance of [effectiveness - 1, bias] per step (bias: 0)
    effectiveness_alarm: Any = math.inf  # loss of effectiveness (less 2 std) that alarms [-]

    def signals(self):
        return (
            Signal("fdi_residual", VEC, "N m", "rigid-body residual (applied - commanded)", "body"),
            *detection_signals("body", "body axis", "body axis"),
            Signal("fdi_flag", VEC, "1", "generalised channel reported faulty (reconfigure)"),
            Signal("fdi_estimate", VEC, "N m", "identified fault u* as a generalised torque"),
            *(identification_signals("body", "body axis") if self.identification == "rls" else ()),
        )

    def initial_state(self, measurement0):
        zeros = jnp.zeros((self.count, 3))
        off = jnp.zeros((self.count, 3), dtype=bool)
        return AttitudeFdiState(
            q_prev=jnp.asarray(measurement0["q"]),
            w_prev=jnp.asarray(measurement0["w"]),
            tau_prev=zeros,
            tau_last=zeros,
            commanded=jnp.asarray(False),
            valid=jnp.asarray(False),
            tested=off,
            f_hat=zeros,
            residual=zeros,
            flag=off,
            **self._test_state(),
        )

    def _identify(self, state: AttitudeFdiState, r, tested):
        """One RLS step of every tested channel on the regressor ``[tau, 1]``; returns ``(theta, cov,
        effectiveness, std, identified)``."""
        regressor = jnp.stack([state.tau_prev, jnp.ones_like(state.tau_prev)], axis=-1)
        noise_var = jnp.broadcast_to(self.identification_noise**2, (3,))
        walked = state.theta_cov + self.walk  # the parameters' random walk over the step
        theta, cov = identify_channels(
            state.theta, walked, r, regressor, noise_var, self.forgetting
        )
        theta = jnp.where(tested[..., None], theta, state.theta)
        cov = jnp.where(tested[..., None, None], cov, walked)
        # no windup: the effectiveness's variance is capped at its prior, by a congruence that keeps
        # what the steps told of the bias (restarting the whole covariance would discard it, and a
        # channel just restarted learns its bias first)
        scale = jnp.sqrt(jnp.minimum(1.0, 1.0 / cov[..., 0, 0]))  # prior variance of e - 1: 1
        d = jnp.stack([scale, jnp.ones_like(scale)], axis=-1)
        cov = cov * d[..., :, None] * d[..., None, :]
        std = jnp.sqrt(jnp.maximum(cov[..., 0, 0], 0.0))
        return theta, cov, 1.0 + theta[..., 0], std, std <= self.identification_std

    def _estimate(self, state: AttitudeFdiState, q, stat, ident) -> AttitudeFdiEstimate:
        W = rbar_inv(q)  # omega = W q_dot; u_bar = W^T f
        body = jnp.where(state.isolated, state.f_hat, 0.0)
        u_star = jnp.einsum("nkp,nk->np", W, body)
        flag = jnp.where(state.flag, 1.0, 0.0)
        return AttitudeFdiEstimate(
            flag=flag,
            estimate=flag * u_star,
            detected=state.detected,
            isolated=state.isolated,
            statistic=stat,
            residual=state.residual,
            identified=state.f_hat,
            **ident,
        )

    def update(self, t, state: AttitudeFdiState, inputs: FlightInputs):
        q, w = inputs.measurement["q"], inputs.measurement["w"]
        J, n = self.nominal_inertia, self.orbit_rate
        r = rigid_body_residual(
            state.q_prev, state.w_prev, q, w, state.tau_prev, J, inputs.step.dt, n
        )
        r = jnp.where(state.valid, r, 0.0)
        # a channel at its rated limit is not tested over the step
        tested = state.valid & state.tested
        z = jnp.where(tested, r / self.residual_std, 0.0)
        g_pos, g_neg, stat, alarm = self._test(state, z)
        rls, score = self.identification == "rls", stat
        if rls:
            theta, cov, eff, std, known = self._identify(state, r, tested)
            # an identified effectiveness below 1 - effectiveness_alarm by two standard deviations
            # alarms too; isolation by the larger of the normalised statistics
            loss = 1.0 - eff - 2.0 * std
            id_score = jnp.where(known, loss / self.effectiveness_alarm, 0.0)
            score = jnp.maximum(stat / self.threshold, id_score)
            alarm = alarm | jnp.any(id_score > 1.0)
        detected, isolated, first = latch_first_alarm(score, alarm, state.detected, state.isolated)
        ident, identification = {}, {}
        if rls:
            restart = first & isolated  # the isolated channel starts again from the prior
            theta, cov = self._restart(theta, cov, restart)
            identification = {"theta": theta, "theta_cov": cov}
            ident = {"effectiveness": eff, "effectiveness_std": std, "known": known & ~restart}
        # the law's channel of the isolated body axis at this attitude (W^T e_k: row k of W)
        weight = jnp.einsum("nk,nkp->np", jnp.where(isolated, 1.0, 0.0), jnp.abs(rbar_inv(q)))
        top = (weight == jnp.max(weight, axis=1, keepdims=True)) & (weight > 0.0)
        flag = jnp.where(first, top, state.flag)
        # identification on every step: after a fault the law's command on the faulty channel may stay
        # above the rated torque (the untested region) while the fault goes on
        f_hat = jnp.where(
            state.valid, state.f_hat + self.smoothing * (r - state.f_hat), state.f_hat
        )
        new = state._replace(
            q_prev=q,
            w_prev=w,
            g_pos=g_pos,
            g_neg=g_neg,
            f_hat=f_hat,
            residual=r,
            detected=detected,
            isolated=isolated,
            flag=flag,
            **identification,
        )
        return new, self._estimate(new, q, stat, ident)

    def predict(self, t, state: AttitudeFdiState, command, dt):
        tau = generalized_to_body_torque(state.q_prev, command)  # R_bar(q_k)^T tau_gen
        mean, end, valid = tau, tau, jnp.asarray(True)
        if self.command == "extrapolated":  # mean over the step of a linearly varying command
            mean, end = 1.5 * tau - 0.5 * state.tau_last, 2.0 * tau - state.tau_last
            valid = state.commanded  # from the second command on (the first step is not tested)
        below = (jnp.abs(tau) < self.torque_limit) & (jnp.abs(end) < self.torque_limit)
        return state._replace(
            tau_prev=mean, tau_last=tau, commanded=jnp.asarray(True), valid=valid, tested=below
        )

    def outputs(self, t, state, estimate: AttitudeFdiEstimate):
        out = {"fdi_residual": estimate.residual}
        out |= detection_outputs(estimate.statistic, estimate.detected, estimate.isolated)
        out |= {"fdi_flag": estimate.flag, "fdi_estimate": estimate.estimate}
        if self.identification == "rls":
            out |= identification_outputs(
                estimate.known, estimate.effectiveness, estimate.effectiveness_std
            )
        return out

    def needs(self) -> dict[str, str]:
        return {
            "euler-angle-measurement": "form the rigid-body residual",
            "euler-angle-law": "map the law's command to the nominal body torque and report in its "
            "channels",
        }


class AttitudeResidualFdiSection(FdiTestSection):
    """Actuator-fault detection, isolation and identification of an Euler-angle attitude law from the
    rigid-body residual (body axes), reported in the law's generalised channels (flag, u*)."""

    nominal_inertia: Inertia = Field(
        MEHRABIAN_NOMINAL_INERTIA,
        description="Principal inertia of the residual's model, known on board [kg m^2] (default 20, "
        "18, 15 kg m^2, the Euler-angle law's default model; a stated value: never the plant's "
        "true inertia).",
    )
    semi_major_axis: float | None = builder_input(
        None,
        gt=0,
        description="Radius of the circular orbit whose LVLH frame the measured attitude and rates are "
        "relative to [m] (adds the frame's rotation and the gravity-gradient torque to the model); "
        "omit for an inertial reference.",
    )
    mu: float = builder_input(MU_EARTH, gt=0, description="Gravitational parameter [m^3/s^2].")
    torque_limit: Annotated[float | list[float] | None, positive_values("limit", " N m")] = Field(
        None,
        description="Rated per-axis body torque [N m], one or per spacecraft: a channel whose nominal "
        "torque reaches it (or would by the step's end) is not tested that step -- a limit may cut "
        "its torque, which the residual cannot tell from a fault; omit for none.",
    )
    residual_std: float = Field(
        gt=0,
        description="Model-error level that standardises the residual, z = r / residual_std [N m] "
        "(discretisation, the command's variation inside the step, inertia error, unmodelled torques).",
    )
    command: Literal["held", "extrapolated"] = Field(
        "extrapolated",
        description="Mean command over a step: held (a sampled law) or extrapolated to the step's "
        "midpoint, 1.5 tau_k - 0.5 tau_k-1 (a law evaluated inside the step, as networked-el-hinf).",
    )
    forgetting: FdiForgetting = 0.999
    bias_prior_std: float = Field(
        0.01,
        gt=0,
        description="Prior standard deviation of a channel's bias torque [N m] (a channel's first "
        "steps pin its bias before the command's variation tells the effectiveness).",
    )
    identification_noise_std: float | None = Field(
        None,
        gt=0,
        description="Residual noise the identification assumes [N m] (default residual_std, which "
        "bounds the acquisition's model error for the alarm test; a settled hold's residual is "
        "smaller, and a smaller excitation is identified as fast against it).",
    )
    effectiveness_walk: float = Field(
        0.0,
        ge=0,
        description="Random walk of the effectiveness [1/sqrt(s)]: process noise of the "
        "identification, so that a fault after a rich acquisition is followed at once; 0: none "
        "(forgetting alone).",
    )
    effectiveness_alarm: float = Field(
        0.1,
        gt=0,
        description="An identified effectiveness below 1 - effectiveness_alarm by two of its standard "
        "deviations raises the alarm (identification = 'rls'; a loss of effectiveness the "
        "residual's mean-shift test cannot see) [-].",
    )
    identification_time: float = builder_input(
        2.0,
        gt=0,
        description="Time constant of the moving average of the residual that identifies the fault's "
        "magnitude [s].",
    )


def _build(sec: AttitudeResidualFdiSection, ctx: BuildContext) -> AttitudeResidualFdi:
    """The estimator of a validated ``[estimator] type = "attitude-residual-fdi"`` section."""
    n = 0.0 if sec.semi_major_axis is None else math.sqrt(sec.mu / sec.semi_major_axis**3)
    m = ctx.count
    limit = np.inf if sec.torque_limit is None else sec.torque_limit
    J = np.diag(np.asarray(sec.nominal_inertia, dtype=float))
    return AttitudeResidualFdi(
        count=m,
        command=sec.command,
        **sec.fdi_fields(),
        nominal_inertia=as_float(np.stack([J] * m)),
        orbit_rate=as_float(n),
        torque_limit=per_spacecraft(limit, m, "estimator.torque_limit")[:, None],
        **section_floats(sec, "residual_std", "effectiveness_alarm"),
        smoothing=as_float(1.0 - math.exp(-ctx.dt / sec.identification_time)),
        identification_noise=as_float(sec.identification_noise_std or sec.residual_std),
        walk=as_float(np.diag([sec.effectiveness_walk**2 * ctx.dt, 0.0])),
    )


register(
    "estimator",
    "attitude-residual-fdi",
    AttitudeResidualFdiSection,
    _build,
    "attitude actuator-fault detection, isolation and identification from the rigid-body residual "
    "(body axes, CUSUM or fixed threshold), reported as (flag, u*) to the Euler-angle law",
)
