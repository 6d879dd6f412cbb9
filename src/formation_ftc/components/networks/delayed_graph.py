"""Network ``delayed-graph``: exchange over a weighted directed graph with time-varying delays T_ij(t)
(Li2020 Thm 2).

The network delivers to spacecraft i the in-weight and the weighted sum of the delayed messages::

    received_i = {"in_weight": sum_j c_ij,  "weighted_sum": sum_j c_ij m_j(t - T_ij(t))}

so that a controller forms ``sum_j c_ij (s_i - s_j(t - T_ij)) = in_weight_i s_i - weighted_sum_i``
(Li2020 eq. (42)); ``T_ij = 0`` delivers what ``graph``
(:class:`~formation_ftc.components.networks.graph.GraphNetwork`) delivers.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any, ClassVar

import jax
import jax.numpy as jnp
import numpy as np
from pydantic import Field

from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.components.networks.graph import GraphSection, graph_edges
from formation_ftc.config.base import ExprText
from formation_ftc.core.expressions import compile_expression
from formation_ftc.core.graph import validate_adjacency
from formation_ftc.core.history import history_init, history_push, history_read, required_capacity
from formation_ftc.sim.components import Network, NetworkInputs, component, static
from formation_ftc.sim.contract import as_float

__all__ = [
    "DelayedGraphNetwork",
    "DelayedGraphSection",
    "DelayStats",
    "delay_statistics",
    "delay_vector_function",
    "delayed_graph_network",
]


@lru_cache(maxsize=256)
def _link_selections(edges: tuple[tuple[int, int], ...], n: int):
    """(receiver rows, sender columns, sender one-hot (E, N), receiver one-hot (N, E)) of the links.
    Cached: every RK stage uses the same constant arrays, so XLA merges the reads of stages 2 and 3."""
    rows = np.array([i for i, _ in edges], dtype=int)
    cols = np.array([j for _, j in edges], dtype=int)
    return rows, cols, np.eye(n)[cols], np.eye(n)[rows].T


@lru_cache(maxsize=256)
def delay_vector_function(texts: tuple[tuple[str, ...], ...], pairs: tuple[tuple[int, int], ...]):
    """``T(t) -> (E,)`` [s]: the delay expressions (in t [s], i receiver, j sender, 1-based) of the listed
    ``pairs`` ((i, j) 0-based), in that order (compiled once per texts and pairs).

    Parameters
    ----------
    texts : tuple of tuple of str
        (N, N) delay expressions T_ij, row i = receiver, giving seconds.
    pairs : tuple of tuple of int
        The links ``(i, j)``, 0-based.

    Returns
    -------
    callable
        ``T(t)`` with t [s] -> jax.Array of shape ``(len(pairs),) + shape(t)`` [s].

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.networks.delayed_graph import delay_vector_function
    >>> texts = (("0", "0.1 + 0.01 * t"), ("0.2 * i", "0"))
    >>> T = delay_vector_function(texts, ((0, 1), (1, 0)))
    >>> np.asarray(T(2.0)).round(12)
    array([0.12, 0.4 ])
    """
    fns = [
        compile_expression(texts[i][j], ("t", "i", "j"), field=f"network.delays[{i}][{j}]")
        for i, j in pairs
    ]

    def T(t):
        return jnp.stack(
            [
                jnp.broadcast_to(f(t=t, i=float(i + 1), j=float(j + 1)), jnp.shape(t))
                for f, (i, j) in zip(fns, pairs, strict=True)
            ]
        )

    return T


@dataclass(frozen=True)
class DelayStats:
    """Extremes of one delay T_ij over the step grid of a horizon (pair (i, j) 0-based receiver, sender)."""

    pair: tuple[int, int]
    t_min: float  # time of min T [s]
    value_min: float  # [s]
    value_max: float  # [s]
    rate_max: float  # max dT/dt [-]
    t_rate_max: float  # [s]
    t_first_negative: float = float("nan")  # first grid time with T < 0 [s]
    t_max: float = float("nan")  # time of max T [s]

    @property
    def name(self) -> str:
        i, j = self.pair
        return f"T{i + 1}{j + 1}"


@lru_cache(maxsize=64)
def delay_statistics(
    texts: tuple[tuple[str, ...], ...], horizon: float, dt: float
) -> tuple[DelayStats, ...]:
    """Values and rates of every off-diagonal delay T_ij(t), sampled at every step t_k = k dt of
    [0, horizon] (the rate dT/dt by forward-mode automatic differentiation).

    Parameters
    ----------
    texts : tuple of tuple of str
        (N, N) delay expressions in t [s], i (receiver) and j (sender), 1-based, giving seconds.
    horizon : float
        End of the grid [s].
    dt : float
        Grid step [s].

    Returns
    -------
    tuple of DelayStats
        One per pair (i, j), i != j, row-major order. Sampled: a violation found is real, a bound is
        not proven between the samples.

    Examples
    --------
    >>> from formation_ftc.components.networks.delayed_graph import delay_statistics
    >>> st = delay_statistics((("0", "1 + 0.5*t"), ("2 - 0.1*t", "0")), 10.0, 0.5)
    >>> [(s.name, s.value_min, s.value_max, round(s.rate_max, 12)) for s in st]
    [('T12', 1.0, 6.0, 0.5), ('T21', 1.0, 2.0, -0.1)]
    """
    n = len(texts)
    pairs = tuple((i, j) for i in range(n) for j in range(n) if i != j)
    vec = delay_vector_function(texts, pairs)
    grid = jnp.arange(int(round(horizon / dt)) + 1, dtype=jnp.float64) * dt

    @jax.jit
    def evaluate(tt):
        return jax.vmap(vec)(tt), jax.vmap(jax.jacfwd(vec))(tt)

    vals, rates = (np.asarray(a) for a in evaluate(grid))
    tg = np.asarray(grid)
    out = []
    for k, pair in enumerate(pairs):
        v, r = vals[:, k], rates[:, k]
        kmin, kmax, kr = int(np.argmin(v)), int(np.argmax(v)), int(np.argmax(r))
        neg = np.flatnonzero(v < 0)
        first_negative = float(tg[neg[0]]) if neg.size else float("nan")
        t_min, lo, hi, rate, t_rate = (
            float(a) for a in (tg[kmin], v[kmin], v[kmax], r[kr], tg[kr])
        )
        out.append(DelayStats(pair, t_min, lo, hi, rate, t_rate, first_negative, float(tg[kmax])))
    return tuple(out)


@component
class DelayedGraphNetwork(Network):
    """Exchange over a weighted directed graph with time-varying delays T_ij(t) [s] (Li2020 Thm 2).

    Every step the message of t_k is pushed into a ring buffer of ``capacity`` samples
    (:mod:`formation_ftc.core.history`); at a stage time t in [t_k, t_k + dt] receiver i reads
    m_j(t - T_ij(t)) with linear interpolation between the stored samples (constant prehistory m_j(t0)).
    The newest stored sample is m(t_k): a delay shorter than the elapsed part of the step
    (0 <= T < t - t_k) interpolates linearly between m_j(t_k) and the message m_j(t) sent now, so
    T = 0 delivers exactly the instantaneous message (as :class:`GraphNetwork`). Requires T_ij(t) >= 0
    and ``capacity >= ceil(max T / dt) + 2``. The per-link reads are dense one-hot selections (faster
    than gathers and scatters on XLA:CPU)."""

    adjacency: Any  # (N, N) c_ij, row i = receiver
    delays: tuple[tuple[str, ...], ...] = static()  # T_ij(t) expressions in t, i, j [s] (N x N)
    edges: tuple[tuple[int, int], ...] = static()  # used links (i, j), see graph_edges
    capacity: int = static()  # ring-buffer length [samples]
    #: False when every used link's delay is known to stay >= dt (e.g. validated by the scenario): the
    #: reads then never need the message sent now, and that per-stage selection is left out
    short_delays: bool = static(default=True)
    delayed: ClassVar[bool] = True

    @property
    def count(self) -> int:
        return int(np.shape(self.adjacency)[0])

    def exogenous(self, t):
        return {"T": delay_vector_function(self.delays, self.edges)(t)}

    def initial_state(self, messages0):
        return history_init(messages0, self.capacity)

    def push(self, state, messages):
        return history_push(state, messages)

    def receive(self, t, state, inputs: NetworkInputs):
        # the one-hot link selections of the senders (E, N) and of the receivers (N, E)
        rows, _, sender_onehot, receiver_onehot = _link_selections(self.edges, self.count)
        C = self.adjacency
        T = inputs.exogenous["T"]
        elapsed = t - inputs.step.t
        # steps before the newest sample m(t_k) (read clamps at 0: the newest sample); the history
        # is sampled at the loop's step
        lag = (T - elapsed) / inputs.step.dt
        # (E, N, d): every sender's message at each link's delayed time
        rows_all = history_read(state, lag)
        m_j = jnp.einsum("en,enk->ek", sender_onehot, rows_all)  # (E, d): m_{j_e}(t - T_e)
        if self.short_delays:
            # T < t - t_k: between m(t_k) and the message sent now, weight
            # w = (t - T - t_k) / (t - t_k) (w = 1 exactly for T = 0); links with T >= t - t_k keep
            # the stored value unchanged
            recent = T < elapsed
            w = jnp.where(recent, (elapsed - T) / jnp.where(recent, elapsed, 1.0), 0.0)[:, None]
            m_now = jnp.einsum("en,nk->ek", sender_onehot, inputs.messages)  # (E, d): m_{j_e}(t)
            m_j = jnp.where(recent[:, None], (1.0 - w) * m_j + w * m_now, m_j)
        c_e = jnp.sum(C[rows] * sender_onehot, axis=1)  # (E,) link weights c_{i_e j_e}
        weighted = receiver_onehot @ (c_e[:, None] * m_j)  # (N, d), eq. (42)
        return {"in_weight": jnp.sum(C, axis=1), "weighted_sum": weighted}


class DelayedGraphSection(GraphSection):
    """The weighted directed graph of ``graph`` with a delay expression per link; ``max_delay`` sizes
    the history buffer (the builder turns it into the network's ``capacity``)."""

    delays: list[list[ExprText]] = Field(
        description="T_ij(t) per link, expressions in t, i (receiver), j (sender) [s] (N x N, row i = "
        "receiver; the diagonal and unused links are not read); >= 0 on the used links."
    )
    max_delay: float = builder_input(
        gt=0, description="Largest delay on any used link [s] (sizes the history buffer)."
    )


def delayed_graph_network(sec: DelayedGraphSection, ctx: BuildContext) -> DelayedGraphNetwork:
    """The network of a validated ``delayed-graph`` section (also the delayed base of other graph
    networks: any section with ``adjacency``, ``delays`` and ``max_delay``).

    The delays of the used links, sampled at every step of the horizon, must stay in [0, max_delay]
    (the history holds max_delay seconds); when they also stay >= dt the reads never need the message
    sent within the step, and that blend is left out (``short_delays``).

    Parameters
    ----------
    sec : DelayedGraphSection
        The validated section.
    ctx : BuildContext
        The spacecraft count, the step and the horizon.

    Returns
    -------
    DelayedGraphNetwork
        The network.

    Raises
    ------
    ValueError
        ``network.delays`` not N x N, or a used link's delay outside [0, max_delay] on the step grid.

    Examples
    --------
    Spacecraft 1 hears spacecraft 2 with a constant 0.25 s delay (dt = 0.1 s, a 1 s horizon):

    >>> from types import SimpleNamespace
    >>> from formation_ftc.components._registry import BuildContext
    >>> ctx = BuildContext(SimpleNamespace(simulation=SimpleNamespace(horizon=1.0)), count=2, dt=0.1)
    >>> sec = DelayedGraphSection(adjacency=[[0.0, 1.0], [0.0, 0.0]], delays=[["0", "0.25"], ["0", "0"]],
    ...                           max_delay=0.5)
    >>> net = delayed_graph_network(sec, ctx)
    >>> net.edges, net.short_delays  # the delay never drops below dt: no blend with the message sent now
    (((0, 1),), False)
    >>> delayed_graph_network(sec.model_copy(update={"delays": [["0", "0.25 + t"], ["0", "0"]]}), ctx)
    Traceback (most recent call last):
    ...
    ValueError: network.delays[0][1] (T12, link 2 -> 1): T = 1.25 s at t = 1 s exceeds network.max_delay = 0.5 s (the history holds max_delay seconds)
    """
    n = len(validate_adjacency(sec.adjacency, ctx.count))
    if len(sec.delays) != n or any(len(r) != n for r in sec.delays):
        raise ValueError(f"network.delays: must be {n} x {n} like network.adjacency")
    edges = graph_edges(sec.adjacency)
    texts = tuple(tuple(str(x) for x in r) for r in sec.delays)
    stats = {st.pair: st for st in delay_statistics(texts, ctx.horizon, ctx.dt)}
    for i, j in edges:
        st = stats[(i, j)]
        where = f"network.delays[{i}][{j}] ({st.name}, link {j + 1} -> {i + 1})"
        if st.value_min < 0:
            raise ValueError(
                f"{where}: delay goes negative at t = {st.t_first_negative:.6g} s (minimum "
                f"T = {st.value_min:.6g} s at t = {st.t_min:.6g} s; delays must be >= 0 s)"
            )
        if st.value_max > sec.max_delay:
            raise ValueError(
                f"{where}: T = {st.value_max:.6g} s at t = {st.t_max:.6g} s exceeds "
                f"network.max_delay = {sec.max_delay:g} s (the history holds max_delay seconds)"
            )
    return DelayedGraphNetwork(
        adjacency=as_float(sec.adjacency),
        delays=texts,
        edges=edges,
        capacity=required_capacity(sec.max_delay, ctx.dt) + 1,
        short_delays=any(stats[e].value_min < ctx.dt for e in edges),
    )


register(
    "network",
    "delayed-graph",
    DelayedGraphSection,
    delayed_graph_network,
    "weighted directed graph with time-varying delays (history buffer, interpolation)",
)
