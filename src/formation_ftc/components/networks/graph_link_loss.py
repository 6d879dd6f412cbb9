"""Network ``graph-link-loss``: communication faults on a weighted graph (optionally delayed), links
lost after an onset, delays scaled after it.

``[network] type = "graph-link-loss"``: the ``graph`` fields (``adjacency``), optionally ``delays`` and
``max_delay`` of ``delayed-graph``, plus ``lost_links`` (pairs [i, j], 1-based: receiver i stops hearing
sender j; the component's ``lost`` mask), ``onset`` [s], ``delay_scale`` [-] and ``max_delay_scale``
[-] (delayed graphs only).

From the first step whose start time ``t_k >= onset`` [s] on, every link (i <- j) marked in ``lost``
(an (N, N) mask, 1 = lost, row i = receiver as the weights) stops delivering: its weight becomes 0,
so receiver i's in-weight and weighted sum count one neighbour fewer::

    c_ij(t) = c_ij (1 - lost_ij [t_k >= onset])

For the delayed graph every delay is multiplied by ``delay_scale`` [-] over the same steps:
``T_ij(t) -> delay_scale T_ij(t)`` (the history buffer must hold the scaled delays). The onset, the
mask and the scale are array leaves (a league batches link-loss and link-healthy cases in one
compiled program); the reading itself is that of
:class:`~formation_ftc.components.networks.graph.GraphNetwork` /
:class:`~formation_ftc.components.networks.delayed_graph.DelayedGraphNetwork`.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import jax.numpy as jnp
import numpy as np
from pydantic import Field, ValidationInfo, field_validator, model_validator

from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.components.networks.delayed_graph import (
    DelayedGraphNetwork,
    delayed_graph_network,
)
from formation_ftc.components.networks.graph import GraphNetwork, GraphSection
from formation_ftc.config.base import ExprText
from formation_ftc.sim.components import NetworkInputs, component
from formation_ftc.sim.contract import as_float

__all__ = [
    "GraphLinkLossNetwork",
    "DelayedGraphLinkLossNetwork",
    "GraphLinkLossSection",
    "faulty_weights",
]


def faulty_weights(weights, lost, onset, t_k):
    """``c_ij (1 - lost_ij [t_k >= onset])`` [-]: the weights in force over the step starting at ``t_k`` [s].

    Parameters
    ----------
    weights : array_like, shape (N, N)
        Link weights c_ij, row i = receiver [-].
    lost : array_like, shape (N, N)
        1 where the link (i <- j) is lost after the onset [-].
    onset : float
        Onset of the link loss [s].
    t_k : float or jax.Array
        Start of the step [s].

    Returns
    -------
    jax.Array, shape (N, N)
        The weights in force [-].

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.networks.graph_link_loss import faulty_weights
    >>> w, lost = np.array([[0.0, 1.0], [1.0, 0.0]]), np.array([[0.0, 1.0], [0.0, 0.0]])
    >>> np.asarray(faulty_weights(w, lost, onset=5.0, t_k=4.0))
    array([[0., 1.],
           [1., 0.]])
    >>> np.asarray(faulty_weights(w, lost, onset=5.0, t_k=5.0))
    array([[0., 0.],
           [1., 0.]])
    """
    return jnp.where(t_k >= onset, weights * (1.0 - lost), weights)


@component
class GraphLinkLossNetwork(GraphNetwork):
    """:class:`GraphNetwork` whose links marked in ``lost`` (N, N) [-] stop delivering from ``onset`` [s]."""

    lost: Any = 0.0  # (N, N) 1 = link (i <- j) lost after the onset [-]
    onset: Any = float("inf")  # [s]

    def receive(self, t, state, inputs: NetworkInputs):
        w = faulty_weights(self.adjacency, self.lost, self.onset, inputs.step.t)
        return GraphNetwork.receive(dataclasses.replace(self, adjacency=w), t, state, inputs)


@component
class DelayedGraphLinkLossNetwork(DelayedGraphNetwork):
    """:class:`DelayedGraphNetwork` whose links marked in ``lost`` (N, N) [-] stop delivering and whose
    delays are multiplied by ``delay_scale`` [-] from ``onset`` [s] on."""

    lost: Any = 0.0  # (N, N) [-]
    onset: Any = float("inf")  # [s]
    delay_scale: Any = 1.0  # [-]

    def receive(self, t, state, inputs: NetworkInputs):
        after = inputs.step.t >= self.onset
        w = faulty_weights(self.adjacency, self.lost, self.onset, inputs.step.t)
        T = inputs.exogenous["T"] * jnp.where(after, self.delay_scale, 1.0)
        faulty, exogenous = dataclasses.replace(self, adjacency=w), {**inputs.exogenous, "T": T}
        return DelayedGraphNetwork.receive(faulty, t, state, inputs._replace(exogenous=exogenous))


class GraphLinkLossSection(GraphSection):
    """A graph (optionally delayed) whose listed links stop delivering, and delays scale, from ``onset``."""

    delays: list[list[ExprText]] | None = Field(
        None,
        description="T_ij(t) per link, expressions in t, i, j [s] (N x N), >= 0; omit: no delays.",
    )
    max_delay: float | None = builder_input(
        None, gt=0, description="Largest unscaled delay on any used link [s] (with delays)."
    )
    lost_links: list[tuple[int, int]] = builder_input(
        default_factory=list,
        description="Links [i, j] (1-based) that stop delivering: receiver i no longer hears j.",
    )
    onset: float = Field(0.0, ge=0.0, description="Onset of the communication fault [s].")
    delay_scale: float = Field(
        1.0,
        gt=0.0,
        description="Every delay is multiplied by this after the onset [-] (delayed graphs only).",
    )
    max_delay_scale: float | None = builder_input(
        None,
        gt=0.0,
        description="Largest delay_scale the history buffer must serve [-] (default: delay_scale); "
        "give the batch's largest so cases of several scales share one program.",
    )

    @field_validator("lost_links")
    @classmethod
    def _links(cls, v, info: ValidationInfo):
        adjacency = info.data.get("adjacency") or []
        n = len(adjacency)
        for k, (i, j) in enumerate(v):
            if not (1 <= i <= n and 1 <= j <= n):
                raise ValueError(
                    f"lost_links[{k}] = [{i}, {j}]: spacecraft numbers must be in 1..{n}"
                )
            if not (len(adjacency[i - 1]) >= j and adjacency[i - 1][j - 1] > 0):
                raise ValueError(
                    f"lost_links[{k}] = [{i}, {j}]: adjacency[{i - 1}][{j - 1}] = 0, "
                    f"spacecraft {i} does not receive from {j}"
                )
        return v

    @field_validator("delay_scale")
    @classmethod
    def _scale(cls, v, info: ValidationInfo):
        if info.data.get("delays") is None and v != 1.0:
            raise ValueError(
                f"delay_scale = {v}: the graph has no delays to scale (give delays and max_delay, "
                "or delay_scale = 1)"
            )
        return v

    @model_validator(mode="after")
    def _delays(self):
        if (self.delays is None) != (self.max_delay is None):
            raise ValueError("delays and max_delay: give both (delayed graph) or neither")
        if self.max_delay_scale is not None and self.max_delay_scale < self.delay_scale:
            raise ValueError(
                f"max_delay_scale = {self.max_delay_scale} must be >= delay_scale = {self.delay_scale}"
            )
        return self

    def lost_mask(self) -> np.ndarray:
        """(N, N) mask, 1 where link (i <- j) is lost [-]."""
        n = len(self.adjacency)
        mask = np.zeros((n, n))
        for i, j in self.lost_links:
            mask[i - 1, j - 1] = 1.0
        return mask


def _build(
    sec: GraphLinkLossSection, ctx: BuildContext
) -> GraphLinkLossNetwork | DelayedGraphLinkLossNetwork:
    """The network of a validated ``[network] type = "graph-link-loss"`` section."""
    from formation_ftc.core.history import required_capacity

    lost, onset = as_float(sec.lost_mask()), as_float(sec.onset)
    if sec.delays is None:
        return GraphLinkLossNetwork(adjacency=as_float(sec.adjacency), lost=lost, onset=onset)
    base = delayed_graph_network(sec, ctx)  # type: ignore[arg-type]  # same adjacency / delays / max_delay fields
    # the history holds the scaled delays too
    scale = sec.delay_scale if sec.max_delay_scale is None else sec.max_delay_scale
    capacity = required_capacity(float(sec.max_delay or 0.0) * max(1.0, scale), ctx.dt) + 1
    return DelayedGraphLinkLossNetwork(
        adjacency=base.adjacency,
        delays=base.delays,
        edges=base.edges,
        capacity=capacity,
        lost=lost,
        onset=onset,
        delay_scale=as_float(sec.delay_scale),
    )


register(
    "network",
    "graph-link-loss",
    GraphLinkLossSection,
    _build,
    "weighted directed graph (optionally delayed) whose listed links stop delivering, and "
    "whose delays scale, after an onset",
)
