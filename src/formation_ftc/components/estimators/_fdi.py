"""What the residual FDIs share (``residual-fdi``, ``attitude-residual-fdi``): the section fields of
the sequential test per (spacecraft, axis), its drift and threshold and the identification; the
test, the first-alarm latch and the recursive least squares of every channel (pure functions of
arrays); and the recorded FDI signals."""

from __future__ import annotations

from typing import Annotated, Any, Literal

import jax
import jax.numpy as jnp
from pydantic import Field

from formation_ftc.components._sections import section_floats
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import Estimator, Signal
from formation_ftc.sim.contract import VEC

__all__ = [
    "FdiForgetting",
    "FdiTestSection",
    "FdiEstimator",
    "sequential_test",
    "latch_first_alarm",
    "identify_channels",
    "rls_prior",
    "detection_signals",
    "identification_signals",
    "detection_outputs",
    "identification_outputs",
]


FdiForgetting = Annotated[
    float,
    Field(
        gt=0,
        le=1,
        description="RLS forgetting factor lambda; the memory is about 1 / (1 - lambda) steps [-].",
    ),
]


class FdiTestSection(StrictModel):
    """The section fields both residual FDIs state alike: the sequential test per (spacecraft, axis)
    and the identification."""

    test: Literal["cusum", "fixed"] = Field(
        "cusum",
        description="Test per (spacecraft, axis): Page's two-sided CUSUM or |z| > threshold.",
    )
    drift: float = Field(
        0.5, ge=0, description="CUSUM drift (half the standardised shift to detect) [-]."
    )
    threshold: float = Field(
        20.0, gt=0, description="Alarm threshold on the statistic (CUSUM g, or |z|) [-]."
    )
    identification: Literal["off", "rls"] = Field(
        "off",
        description="Fault identification: off, or each channel's effectiveness and bias by recursive "
        "least squares with exponential forgetting on the residual (provides fault-identification).",
    )
    identification_std: float = Field(
        0.05,
        gt=0,
        description="Standard deviation of a channel's effectiveness estimate at or below which the "
        "channel counts as identified (before: reported as NaN) [-].",
    )

    def fdi_fields(self) -> dict[str, Any]:
        """The fields of an :class:`FdiEstimator` this section (with its ``forgetting`` and
        ``bias_prior_std``) states."""
        return dict(
            **self.model_dump(include={"test", "identification"}),
            **section_floats(self, "drift", "threshold", "forgetting"),
            **section_floats(self, "identification_std", "bias_prior_std"),
        )


class FdiEstimator(Estimator):
    """What the residual FDI components share: the test statistics and first-alarm latch of their
    state, the test step, the RLS prior and its restart, and what they provide. A subclass states
    the fields below (and ``forgetting``, ``identification_std``)."""

    count: int
    test: str  # "cusum" or "fixed"
    drift: Any  # CUSUM drift [-]
    threshold: Any  # alarm threshold [-]
    identification: str  # "off" or "rls"
    bias_prior_std: Any  # prior standard deviation of a channel's bias

    def provides(self) -> frozenset[str]:
        rls = self.identification == "rls"
        return frozenset({"fdi-records"} | ({"fault-identification"} if rls else set()))

    def _test_state(self) -> dict[str, Any]:
        """The initial statistics and latch, and with identification the RLS prior."""
        zeros = jnp.zeros((self.count, 3))
        state = {"g_pos": zeros, "g_neg": zeros, "detected": jnp.asarray(False)}
        state["isolated"] = jnp.zeros((self.count, 3), dtype=bool)
        if self.identification == "rls":
            state["theta"], state["theta_cov"] = self._prior()
        return state

    def _test(self, state, z):
        """:func:`sequential_test` of ``z`` from the statistics of ``state``."""
        return sequential_test(self.test, state.g_pos, state.g_neg, z, self.drift, self.threshold)

    def _prior(self):
        return rls_prior(self.count, self.bias_prior_std)

    def _restart(self, theta, cov, restart):
        """``(theta, cov)`` with the channels ``restart`` back at the prior."""
        theta0, cov0 = self._prior()
        theta = jnp.where(restart[..., None], theta0, theta)
        return theta, jnp.where(restart[..., None, None], cov0, cov)


def sequential_test(test: str, g_pos, g_neg, z, drift, threshold):
    """One step of the test on standardised residuals ``z`` of every channel.

    ``cusum``: Page's two-sided CUSUM ``g+ = max(0, g+ + z - drift)``, ``g- = max(0, g- - z - drift)``,
    statistic ``max(g+, g-)``; ``fixed``: statistic ``|z|`` (``g+``, ``g-`` returned unchanged).

    Parameters
    ----------
    test : str
        ``"cusum"`` or ``"fixed"``.
    g_pos, g_neg : array_like
        CUSUM statistics of a positive / negative shift before this step, shape of ``z`` [-].
    z : array_like
        Standardised residual of every channel [-].
    drift : float
        CUSUM drift [-].
    threshold : float
        Alarm threshold on the statistic [-].

    Returns
    -------
    tuple
        ``(g_pos, g_neg, statistic, alarm)``: the updated statistics, the test statistic per channel
        and ``alarm`` () true when any statistic exceeds ``threshold``.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.estimators._fdi import sequential_test
    >>> g = np.zeros(2)
    >>> g_pos, g_neg, stat, alarm = sequential_test("cusum", g, g, np.array([3.0, -1.0]), 0.5, 2.0)
    >>> stat.tolist(), bool(alarm)
    ([2.5, 0.5], True)
    """
    if test == "cusum":
        g_pos = jnp.maximum(0.0, g_pos + z - drift)
        g_neg = jnp.maximum(0.0, g_neg - z - drift)
        stat = jnp.maximum(g_pos, g_neg)
    else:
        stat = jnp.abs(z)
    return g_pos, g_neg, stat, jnp.any(stat > threshold)


def latch_first_alarm(stat, alarm, detected, isolated):
    """Latches the first alarm and isolates the channel with the largest statistic at that step.

    Parameters
    ----------
    stat : array_like
        Test statistic of every channel at this step [-].
    alarm : array_like, shape ()
        An alarm at this step.
    detected : array_like, shape ()
        The latched alarm before this step.
    isolated : array_like
        The latched one-hot channel before this step (shape of ``stat``, bool).

    Returns
    -------
    tuple
        ``(detected, isolated, first)``: the latched alarm, the one-hot channel of the largest
        statistic at the first alarm (held afterwards) and ``first`` () true at the first alarm's step.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.estimators._fdi import latch_first_alarm
    >>> none = np.zeros((2, 3), dtype=bool)
    >>> stat = np.array([[0.0, 5.0, 1.0], [2.0, 0.0, 0.0]])
    >>> det, iso, first = latch_first_alarm(stat, np.array(True), np.array(False), none)
    >>> bool(det), bool(first), np.argwhere(iso).tolist()
    (True, True, [[0, 1]])
    >>> det, iso, first = latch_first_alarm(stat[::-1], np.array(True), det, iso)
    >>> bool(first), np.argwhere(iso).tolist()
    (False, [[0, 1]])
    """
    first = alarm & ~detected
    top = jnp.arange(stat.size).reshape(stat.shape) == jnp.argmax(stat)
    return detected | alarm, jnp.where(first, top, isolated), first


def identify_channels(theta, cov, residual, regressor, noise_var, forgetting):
    """One step of recursive least squares with exponential forgetting on every actuator channel.

    The velocity part of the parity residual of channel (i, j) over a window is, for an actuator that
    delivers ``effectiveness * a + bias`` instead of the commanded acceleration ``a``::

        e_ij = phi_ij' [effectiveness_ij - 1, bias_ij] + v_ij,     v_ij ~ N(0, noise_var_j)

    with the regressor ``phi_ij = [s_ij, c_j]``: ``s_ij`` the velocity the commands of the window add
    along j (for one step, ``gamma[3 + j, j] a_ij``, about ``dt a``), ``c_j`` the velocity a unit
    acceleration held over the window adds. With ``theta = [effectiveness - 1, bias]`` the update is
    the Kalman filter of a parameter that drifts as the forgetting factor lambda allows (Ljung &
    Soderstrom, *Theory and Practice of Recursive Identification*, 1983, ch. 2)::

        P- = P / lambda,   K = P- phi / (noise_var + phi' P- phi),
        theta <- theta + K (e - phi' theta),   P <- (I - K phi') P-

    so ``P`` is the covariance of ``theta``; the memory is about ``1 / (1 - lambda)`` steps. The bias
    term also absorbs the on-board model's slowly varying error (a CW model on a J2 orbit). A command
    that stays constant makes ``a`` and ``1`` collinear: ``P`` then stays large along the unexcited
    direction, which is how an unidentifiable channel shows (``effectiveness_std``).

    Parameters
    ----------
    theta : array_like, shape (N, 3, 2)
        ``[effectiveness - 1, bias]`` per channel before this step ([-], [m/s^2]).
    cov : array_like, shape (N, 3, 2, 2)
        Their covariance.
    residual : array_like, shape (N, 3)
        Velocity part of the parity residual [m/s].
    regressor : array_like, shape (N, 3, 2)
        ``phi_ij = [s_ij, c_j]`` [m/s, s].
    noise_var : array_like, shape (3,)
        Variance of the residual's velocity components [(m/s)^2].
    forgetting : float
        lambda, 0 < lambda <= 1 [-].

    Returns
    -------
    tuple
        ``(theta, cov)`` after this step.

    Examples
    --------
    A channel at half effectiveness, commanded a varying acceleration, noise-free:

    >>> import numpy as np
    >>> theta, cov = np.zeros((1, 1, 2)), np.eye(2)[None, None] * np.array([1.0, 1e-4])[:, None]
    >>> for k in range(50):
    ...     a = np.array([[1e-3 * (1 + (k % 2))]])
    ...     e = 0.1 * (0.5 - 1.0) * a
    ...     phi = 0.1 * np.stack([a, np.ones_like(a)], axis=-1)
    ...     theta, cov = identify_channels(theta, cov, e, phi, np.array([1e-12]), 1.0)
    >>> round(float(1 + theta[0, 0, 0]), 4)
    0.5
    """
    phi = regressor
    prior = cov / forgetting
    p_phi = jnp.einsum("ncab,ncb->nca", prior, phi)
    s = noise_var[None, :] + jnp.einsum("nca,nca->nc", phi, p_phi)
    k = p_phi / s[..., None]
    innovation = residual - jnp.einsum("nca,nca->nc", phi, theta)
    theta = theta + k * innovation[..., None]
    cov = prior - jnp.einsum("nca,ncb->ncab", k, p_phi)
    return theta, 0.5 * (cov + jnp.swapaxes(cov, -1, -2))


def rls_prior(count: int, bias_prior_std) -> tuple[jax.Array, jax.Array]:
    """Prior of every channel's ``theta = [effectiveness - 1, bias]`` for :func:`identify_channels`:
    0 +- (1, ``bias_prior_std``), uncorrelated.

    Parameters
    ----------
    count : int
        Spacecraft N (3 channels each).
    bias_prior_std : float
        Prior standard deviation of a channel's bias (its units: m/s^2 or N m).

    Returns
    -------
    tuple of jax.Array
        ``(theta, cov)``, shapes (N, 3, 2) and (N, 3, 2, 2).

    Examples
    --------
    >>> theta, cov = rls_prior(1, 0.1)
    >>> theta.shape, cov[0, 0].tolist()
    ((1, 3, 2), [[1.0, 0.0], [0.0, 0.010000000000000002]])
    """
    cov = jnp.diag(jnp.stack([jnp.ones(()), jnp.asarray(bias_prior_std) ** 2]))
    return jnp.zeros((count, 3, 2)), jnp.broadcast_to(cov, (count, 3, 2, 2))


def detection_signals(frame: str, axis: str, channel: str) -> tuple[Signal, ...]:
    """The recorded detection signals ``fdi_statistic``, ``fdi_detected`` and ``fdi_isolated``.

    Parameters
    ----------
    frame : str
        Frame of the channels' axes (``"LVLH"``, ``"body"``).
    axis : str
        What the second index of a channel is called (``"axis"``, ``"body axis"``).
    channel : str
        What a channel is called (``"channel"``, ``"body axis"``).

    Returns
    -------
    tuple of Signal
        The three signals, in this order.

    Examples
    --------
    >>> [s.name for s in detection_signals("LVLH", "axis", "channel")]
    ['fdi_statistic', 'fdi_detected', 'fdi_isolated']
    """
    return (
        Signal(
            "fdi_statistic",
            VEC,
            "1",
            f"test statistic per spacecraft and {axis} (CUSUM max(g+, g-), or |z|)",
            frame,
        ),
        Signal("fdi_detected", (), "1", "1 from the first alarm on (latched)"),
        Signal("fdi_isolated", VEC, "1", f"one-hot {channel} isolated at the first alarm", frame),
    )


def identification_signals(frame: str, channel: str) -> tuple[Signal, ...]:
    """The recorded identification signals ``fdi_effectiveness`` and ``fdi_effectiveness_std``.

    Parameters
    ----------
    frame : str
        Frame of the channels' axes (``"LVLH"``, ``"body"``).
    channel : str
        What a channel is called (``"channel"``, ``"body axis"``).

    Returns
    -------
    tuple of Signal
        The two signals, in this order.

    Examples
    --------
    >>> identification_signals("body", "body axis")[0].long_name
    'identified actuator effectiveness per body axis (NaN: not identified)'
    """
    return (
        Signal(
            "fdi_effectiveness",
            VEC,
            "1",
            f"identified actuator effectiveness per {channel} (NaN: not identified)",
            frame,
        ),
        Signal(
            "fdi_effectiveness_std",
            VEC,
            "1",
            "standard deviation of the identified effectiveness",
            frame,
        ),
    )


def detection_outputs(statistic, detected, isolated) -> dict[str, jax.Array]:
    """The values of :func:`detection_signals` at a step.

    Parameters
    ----------
    statistic : array_like
        Test statistic of every channel [-].
    detected : array_like, shape ()
        The latched alarm.
    isolated : array_like
        The latched one-hot channel (bool).

    Returns
    -------
    dict of jax.Array
        ``fdi_statistic``, ``fdi_detected`` and ``fdi_isolated`` (1.0 / 0.0).

    Examples
    --------
    >>> import numpy as np
    >>> out = detection_outputs(np.zeros(2), np.array(True), np.array([False, True]))
    >>> float(out["fdi_detected"]), out["fdi_isolated"].tolist()
    (1.0, [0.0, 1.0])
    """
    return {
        "fdi_statistic": statistic,
        "fdi_detected": jnp.where(detected, 1.0, 0.0),
        "fdi_isolated": jnp.where(isolated, 1.0, 0.0),
    }


def identification_outputs(identified, effectiveness, effectiveness_std) -> dict[str, jax.Array]:
    """The values of :func:`identification_signals` at a step: NaN where a channel is not identified.

    Parameters
    ----------
    identified : array_like
        Channels whose effectiveness is identified (bool).
    effectiveness, effectiveness_std : array_like
        The identified effectiveness of every channel and its standard deviation [-].

    Returns
    -------
    dict of jax.Array
        ``fdi_effectiveness`` and ``fdi_effectiveness_std``.

    Examples
    --------
    >>> import numpy as np
    >>> out = identification_outputs(np.array([True, False]), np.array([0.5, 0.9]), np.ones(2))
    >>> out["fdi_effectiveness"].tolist()
    [0.5, nan]
    """
    return {
        "fdi_effectiveness": jnp.where(identified, effectiveness, jnp.nan),
        "fdi_effectiveness_std": effectiveness_std,
    }
