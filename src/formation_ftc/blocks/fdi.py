"""Synthetic fault detection, isolation and identification (FDI) with configurable imperfections.

Mehrabian, Tafazoli, Khorasani assume an FDI unit running in parallel with the controller
(Assumption 4) whose output -- a fault flag and an estimate ``u*_j(t)`` of the additive actuator fault
``u_bar_j(t)`` (2) -- may be imperfect in three ways (Sec. IV): *detection* (the fault is missed,
Case 1), *isolation* (reported in the wrong channel or the wrong spacecraft, Case 2) and
*identification* (wrong magnitude, Case 3). This block models such an FDI from the true fault signal;
any controller can consume its :class:`FDIOutput`.

Model (per step k, t = k dt; all numbers in ``params`` so campaigns can vary them)::

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

Flight-side boundary (architecture principle: flight side sees no truth): a controller receives only the :class:`FDIOutput`;
the true fault is read here, on the truth side of the synthetic FDI.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

__all__ = [
    "FDIOutput",
    "FDIModel",
    "fdi_params",
    "identity_routing",
    "isolation_routing",
    "fdi_output",
]


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
    """Correct isolation: routing[j, p, n, q] = 1 iff (j, p) == (n, q)."""
    return np.eye(n_agents * n_channels).reshape(n_agents, n_channels, n_agents, n_channels)


def isolation_routing(
    n_agents: int, n_channels: int, moves: Mapping[tuple[int, int], tuple[int, int]]
) -> np.ndarray:
    """Routing with isolation errors: ``moves[(n, q)] = (j, p)`` reports the fault of spacecraft n,
    channel q (0-based) as if it were in spacecraft j, channel p; other channels are routed correctly.

    Raises ValueError naming the entry when an index is out of range.
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
    fault_mask : (m, k) 1 where the true fault acts [-].
    onset : fault onset time [s]; the FDI activates at onset + delay (snapped to the step grid).
    delay : detection latency [s] (>= 0), also the lag of the reported estimate.
    detected : False models a missed detection (no flag, zero estimate).
    scale, bias, noise_std : identification error, scalars or (m, k) [-, N m, N m].
    routing : (m, k, m, k) isolation map, identity by default.
    presence_threshold : |u_bar| above which a channel counts as faulty [N m].
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
    """FDI output at step ``k`` (int, may be traced). Pure; jit/vmap friendly."""
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
