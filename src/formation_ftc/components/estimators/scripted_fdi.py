"""Estimator ``scripted-fdi``: a synthetic fault detection, isolation and identification (FDI) report
with configurable imperfections (Mehrabian Sec. IV, Assumption 4).

Mehrabian, Tafazoli, Khorasani assume an FDI unit running in parallel with the controller
(Assumption 4) whose output -- a fault flag and an estimate ``u*_j(t)`` of the additive actuator fault
``u_bar_j(t)`` (2) -- may be imperfect in three ways (Sec. IV): *detection* (the fault is missed,
Case 1), *isolation* (reported in the wrong channel or the wrong spacecraft, Case 2) and
*identification* (wrong magnitude, Case 3). This estimator models such an FDI from the scripted
fault; any controller can consume its :class:`FDIOutput`.

Model (per step k, t = k dt; every number a leaf, so campaigns can vary them)::

    k_d      = round(delay / dt)                              detection / identification latency [steps]
    active   = detected * (k >= round((onset + delay) / dt))  latched once detected (missed: detected = 0)
    f        = u_bar(k - k_d)                                 true fault seen with the latency   [N m]
    present  = |f| > presence_threshold                       channels where the (delayed) fault is visible
    raw      = present * (scale * f + bias + noise_std * n_k) identification error, n_k ~ N(0, 1) per step
    u*       = active * routing . raw                         isolation: routing[j, p, n, q] moves
    flag     = active * (routing . fault_mask > 0)            channel (n, q) to the reported (j, p)

``routing`` is the identity for correct isolation; :func:`isolation_routing` builds wrong-channel /
wrong-spacecraft maps. With the Our choice (E003-10) (delay 5 s, scale 1, bias -0.1 N m) the estimate is
``u*_{1,3}(t) = u_bar_{1,3}(t - 5) - 0.1`` on [45, 245] s and 0 elsewhere (E003-10).

The noise sample is held over the step; the caller passes a per-step key that is distinct from the
keys of other random signals (e.g. ``fold_in(fold_in(run_key, k), tag)``).

It is a *scripted* report: the scenario compiles
the same fault description (the actuator's ``faults``: the capability ``scripted-actuator-faults`` of
``euler-torque-allocation``) into the truth-side actuator and into this component's own time profile,
so the estimator reads no truth at run time -- only its own profile and its own noise stream (the
fourth stream of the run seed, ``fold_in(key, k)`` per step). A controller receives only the
:class:`FDIOutput`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from pydantic import Field

from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.components.actuators.euler_torque_allocation import FaultProfile
from formation_ftc.config.base import StrictModel
from formation_ftc.core.disturbances import run_key, step_key
from formation_ftc.core.fault_profiles import windowed_additive_faults
from formation_ftc.sim.components import Estimator, FlightInputs, Signal, component, static
from formation_ftc.sim.contract import VEC, as_float

__all__ = [
    "ScriptedFdi",
    "ScriptedFdiSection",
    "IsolationEntry",
    "FDIOutput",
    "FDIModel",
    "fdi_params",
    "identity_routing",
    "isolation_routing",
    "fdi_output",
    "fdi_noise_key",
]

#: the fields of :func:`fdi_params`, in the order of the component's leaves
PARAMS = (
    "bias",
    "delay",
    "detected",
    "fault_mask",
    "noise_std",
    "onset",
    "presence_threshold",
    "routing",
    "scale",
)


class FDIOutput(NamedTuple):
    """What the FDI hands to the controller (both (m, k) float64)."""

    flag: jax.Array  # 1.0 where a fault is reported (reconfigure this channel), else 0.0 [-]
    estimate: jax.Array  # reported fault estimate u*_j(t) [N m]


@dataclass(frozen=True)
class FDIModel:
    """Structure of the synthetic FDI (static: goes in the compile key).

    Attributes
    ----------
    n_agents, n_channels : m spacecraft and k input channels.
    fault_fn : ``k -> (m, k)`` true additive fault at integer step ``k`` [N m] (jittable; must accept a
        traced int and return 0 for k < 0 when the fault has not started).
    dt : step [s].
    """

    n_agents: int
    n_channels: int
    fault_fn: Callable[[jax.Array], jax.Array]
    dt: float


def identity_routing(n_agents: int, n_channels: int) -> np.ndarray:
    """Correct isolation: ``routing[j, p, n, q] = 1`` iff ``(j, p) == (n, q)``.

    Parameters
    ----------
    n_agents, n_channels : int
        Spacecraft m and channels k.

    Returns
    -------
    numpy.ndarray, shape (m, k, m, k)
        The identity routing [-].

    Examples
    --------
    >>> float(identity_routing(2, 3).reshape(6, 6).trace())
    6.0
    """
    return np.eye(n_agents * n_channels).reshape(n_agents, n_channels, n_agents, n_channels)


def isolation_routing(
    n_agents: int, n_channels: int, moves: Mapping[tuple[int, int], tuple[int, int]]
) -> np.ndarray:
    """Routing with isolation errors: ``moves[(n, q)] = (j, p)`` reports the fault of spacecraft n,
    channel q (0-based) as if it were in spacecraft j, channel p; other channels are routed correctly.

    Parameters
    ----------
    n_agents, n_channels : int
        Spacecraft m and channels k.
    moves : Mapping
        ``(n, q) -> (j, p)``, 0-based.

    Returns
    -------
    numpy.ndarray, shape (m, k, m, k)
        The routing [-].

    Raises
    ------
    ValueError
        An index out of range, naming the entry.

    Examples
    --------
    The fault of spacecraft 1, channel 3 reported in channel 1:

    >>> R = isolation_routing(2, 3, {(0, 2): (0, 0)})
    >>> float(R[0, 0, 0, 2]), float(R[0, 2, 0, 2])
    (1.0, 0.0)
    """
    R = identity_routing(n_agents, n_channels)
    for (n, q), (j, p) in moves.items():
        for name, v, hi in (
            ("spacecraft", n, n_agents),
            ("channel", q, n_channels),
            ("reported spacecraft", j, n_agents),
            ("reported channel", p, n_channels),
        ):
            if not 0 <= v < hi:
                raise ValueError(f"fdi isolation: {name} index {v} out of range 0..{hi - 1}")
        R[:, :, n, q] = 0.0
        R[j, p, n, q] = 1.0
    return R


def fdi_params(
    n_agents: int,
    n_channels: int,
    *,
    fault_mask,
    onset: float,
    delay: float = 0.0,
    detected: bool = True,
    scale=1.0,
    bias=0.0,
    noise_std=0.0,
    routing=None,
    presence_threshold: float = 0.0,
) -> dict[str, np.ndarray]:
    """Parameter pytree of the FDI (float64 numpy arrays, JAX converts them when the run is called;
    vmappable).

    Parameters
    ----------
    n_agents, n_channels : int
        Spacecraft m and channels k.
    fault_mask : array_like, shape (m, k)
        1 where the true fault acts [-].
    onset : float
        Fault onset time [s]; the FDI activates at onset + delay (snapped to the step grid).
    delay : float
        Detection latency [s] (>= 0), also the lag of the reported estimate.
    detected : bool
        False models a missed detection (no flag, zero estimate).
    scale, bias, noise_std : float or array_like, shape (m, k)
        Identification error [-, N m, N m].
    routing : array_like, shape (m, k, m, k), optional
        Isolation map, identity by default.
    presence_threshold : float
        |u_bar| above which a channel counts as faulty [N m].

    Returns
    -------
    dict of numpy.ndarray
        ``fault_mask``, ``onset``, ``delay``, ``detected``, ``scale``, ``bias``, ``noise_std``,
        ``routing``, ``presence_threshold``.

    Examples
    --------
    >>> import numpy as np
    >>> p = fdi_params(2, 3, fault_mask=np.zeros((2, 3)), onset=40.0, delay=5.0, bias=-0.1)
    >>> float(p["delay"]), p["bias"].shape, float(p["detected"])
    (5.0, (2, 3), 1.0)
    """
    if delay < 0:
        raise ValueError(f"fdi.delay must be >= 0 s, got {delay}")
    shape = (n_agents, n_channels)

    def full(v, name):
        a = np.broadcast_to(np.asarray(v, dtype=float), shape).copy()
        if not np.all(np.isfinite(a)):
            raise ValueError(f"fdi.{name} must be finite")
        return a

    if routing is None:
        routing = identity_routing(n_agents, n_channels)
    routing = np.asarray(routing, dtype=float)
    if routing.shape != shape + shape:
        raise ValueError(f"fdi.routing must have shape {shape + shape}, got {routing.shape}")
    if np.any(np.asarray(noise_std) < 0):
        raise ValueError("fdi.noise_std must be >= 0 N m")
    return dict(
        fault_mask=full(fault_mask, "fault_mask"),
        onset=np.asarray(float(onset)),
        delay=np.asarray(float(delay)),
        detected=np.asarray(1.0 if detected else 0.0),
        scale=full(scale, "scale"),
        bias=full(bias, "bias"),
        noise_std=full(noise_std, "noise_std"),
        routing=np.asarray(routing),
        presence_threshold=np.asarray(float(presence_threshold)),
    )


def _route(routing, x):
    return jnp.einsum("jpnq,nq->jp", routing, x)


def fdi_output(model: FDIModel, params: Mapping[str, jax.Array], k, key: jax.Array) -> FDIOutput:
    """The FDI's report at step ``k`` (pure; jit / vmap friendly).

    Parameters
    ----------
    model : FDIModel
        The structure (true fault profile, sizes, step).
    params : Mapping
        The :func:`fdi_params`.
    k : int or jax.Array
        Step index (may be traced).
    key : jax.Array
        The step's key of the identification noise.

    Returns
    -------
    FDIOutput
        Flag and estimate u* (m, k).

    Examples
    --------
    A constant 0.6 N m fault in spacecraft 1, channel 3 from step 0, seen 5 steps late with a bias:

    >>> import jax
    >>> import numpy as np
    >>> mask = np.zeros((1, 3)); mask[0, 2] = 1.0
    >>> model = FDIModel(1, 3, lambda k: jax.numpy.where(k >= 0, 0.6, 0.0) * mask, 1.0)
    >>> p = fdi_params(1, 3, fault_mask=mask, onset=0.0, delay=5.0, bias=-0.1)
    >>> out = fdi_output(model, p, 4, jax.random.key(0))
    >>> np.asarray(out.flag).tolist()
    [[0.0, 0.0, 0.0]]
    >>> np.round(np.asarray(fdi_output(model, p, 5, jax.random.key(0)).estimate), 12).tolist()
    [[0.0, 0.0, 0.5]]
    """
    dt = model.dt
    k = jnp.asarray(k)
    k_delay = jnp.round(params["delay"] / dt).astype(k.dtype)
    k_detect = jnp.round((params["onset"] + params["delay"]) / dt).astype(k.dtype)
    active = params["detected"] * (k >= k_detect).astype(jnp.float64)
    f = model.fault_fn(k - k_delay)
    present = (jnp.abs(f) > params["presence_threshold"]).astype(jnp.float64)
    noise = jax.random.normal(key, (model.n_agents, model.n_channels), dtype=jnp.float64)
    raw = present * (params["scale"] * f + params["bias"] + params["noise_std"] * noise)
    estimate = active * _route(params["routing"], raw)
    flag = active * (_route(params["routing"], params["fault_mask"]) > 0).astype(jnp.float64)
    return FDIOutput(flag=flag, estimate=estimate)


def fdi_noise_key(seed):
    """Root key of the FDI noise: the fourth of the run's four streams (see
    :func:`formation_ftc.components.plants.euler_angle_attitude.seed_streams`).

    Parameters
    ----------
    seed : int or array_like
        The run's seed (uint32) [-].

    Returns
    -------
    jax.Array
        The FDI stream's root key.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.estimators.scripted_fdi import fdi_noise_key
    >>> from formation_ftc.components.plants.euler_angle_attitude import seed_streams
    >>> bool(np.array_equal(fdi_noise_key(7), seed_streams(7)[3]))
    True
    """
    return jax.random.split(run_key(seed), 4)[3]


@component
class ScriptedFdi(Estimator):
    """FDI report (flag, u*) at every step from the scripted fault profile (:func:`fdi_output`).

    Leaves: ``seed`` (uint32), ``windows`` (n_faults, 2) fault windows [s] and the :func:`fdi_params`
    (``bias``, ``delay``, ``detected``, ``fault_mask``, ``noise_std``, ``onset``,
    ``presence_threshold``, ``routing``, ``scale``). Static: the fault expressions, 0-based spacecraft
    / channels, and the number of channels; the step index and the step come with the flight inputs.
    The estimate is an :class:`FDIOutput`. Needs the capability ``scripted-actuator-faults``.
    """

    count: int = static()
    seed: Any = 0
    windows: Any = None
    bias: Any = None
    delay: Any = None
    detected: Any = None
    fault_mask: Any = None
    noise_std: Any = None
    onset: Any = None
    presence_threshold: Any = None
    routing: Any = None
    scale: Any = None
    torques: tuple[str, ...] = static(default=())
    spacecraft: tuple[int, ...] = static(default=())
    channels: tuple[int, ...] = static(default=())
    n_channels: int = static(default=3)

    @property
    def params(self) -> dict[str, Any]:
        """The :func:`fdi_params` of the report."""
        return {name: getattr(self, name) for name in PARAMS}

    def _model(self, dt: float) -> FDIModel:
        profile = (self.windows, self.torques, self.spacecraft, self.channels)

        def fault_fn(k):
            return windowed_additive_faults(k, dt, *profile, self.count, self.n_channels)

        return FDIModel(self.count, self.n_channels, fault_fn, dt)

    def update(self, t, state, inputs: FlightInputs):
        k = inputs.step.k
        return state, fdi_output(
            self._model(inputs.step.dt), self.params, k, step_key(fdi_noise_key(self.seed), k)
        )

    def signals(self):
        return (
            Signal("fdi_flag", VEC, "1", "channel reported faulty by the FDI (reconfigure)"),
            Signal("fdi_estimate", VEC, "N m", "fault estimate u* reported by the FDI"),
        )

    def outputs(self, t, state, estimate):
        return {"fdi_flag": estimate.flag, "fdi_estimate": estimate.estimate}

    def needs(self) -> dict[str, str]:
        return {"scripted-actuator-faults": "report them"}


class IsolationEntry(StrictModel):
    spacecraft: int = Field(ge=1, description="True faulty spacecraft (1-based) [-].")
    channel: int = Field(ge=1, le=3, description="True faulty channel [-].")
    reported_spacecraft: int = Field(ge=1, description="Spacecraft the FDI blames (1-based) [-].")
    reported_channel: int = Field(ge=1, le=3, description="Channel the FDI blames [-].")


class ScriptedFdiSection(StrictModel):
    """FDI report (flag, u*) of the actuator's faults with imperfections."""

    detected: bool = Field(True, description="False models a missed detection.")
    delay: float = Field(
        5.0, ge=0.0, description="Detection latency; the estimate also lags by it [s]."
    )
    scale: float = Field(
        1.0, description="Identification scale error: u* = scale u_bar(t - delay) + bias [-]."
    )
    bias: float = Field(0.0, description="Identification bias while the fault is seen [N m].")
    noise_std: float = Field(
        0.0, ge=0.0, description="Std of a per-step Gaussian identification noise [N m]."
    )
    isolation: list[IsolationEntry] = builder_input(
        default_factory=list, description="Isolation errors: report a true fault elsewhere."
    )


def _build(sec: ScriptedFdiSection, ctx: BuildContext) -> ScriptedFdi:
    """The estimator of a validated ``[estimator] type = "scripted-fdi"`` section: the report of the
    faults the ``[actuator]`` section states (``fault_profile``); without any, a report of none, which
    the loop refuses (it needs ``scripted-actuator-faults``)."""
    m, nch = ctx.count, 3
    describe = getattr(ctx.section("actuator"), "fault_profile", None)
    if callable(describe):
        profile = describe(m)
    else:  # a report of none, a placeholder: validation names the need
        profile = FaultProfile((), (), (), np.zeros((0, 2)), np.zeros((m, nch)), 0.0)
    faulty = set(zip(profile.spacecraft, profile.channels, strict=True))
    moves: dict[tuple[int, int], tuple[int, int]] = {}
    for k, e in enumerate(sec.isolation):
        true = (e.spacecraft - 1, e.channel - 1)  # 0-based
        if true not in faulty and profile.torques:
            raise ValueError(
                f"estimator.isolation[{k}]: spacecraft {e.spacecraft} channel {e.channel} has no fault"
            )
        if max(e.spacecraft, e.reported_spacecraft) > m:
            raise ValueError(f"estimator.isolation[{k}]: spacecraft numbers must be in 1..{m}")
        moves[true] = (e.reported_spacecraft - 1, e.reported_channel - 1)
    params: dict[str, Any] = fdi_params(
        m,
        nch,
        fault_mask=profile.mask,
        onset=profile.onset,
        **sec.model_dump(include={"delay", "detected", "scale", "bias", "noise_std"}),
        routing=isolation_routing(m, nch, moves),
    )
    return ScriptedFdi(
        count=m,
        seed=np.asarray(ctx.scenario.simulation.seed, dtype=np.uint32),
        windows=as_float(profile.windows),
        torques=profile.torques,
        spacecraft=profile.spacecraft,
        channels=profile.channels,
        **params,
    )


register(
    "estimator",
    "scripted-fdi",
    ScriptedFdiSection,
    _build,
    "scripted FDI report (flag, u*) of the actuator's faults: latency, missed detection, "
    "isolation and identification errors",
)
