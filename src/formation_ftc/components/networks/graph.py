"""Network ``graph``: instantaneous exchange over a weighted directed graph.

The network delivers to spacecraft i the in-weight and the weighted sum of the messages it receives::

    received_i = {"in_weight": sum_j c_ij,  "weighted_sum": sum_j c_ij m_j(t)}

so that a controller forms the Laplacian consensus term ``sum_j c_ij (s_i - s_j) = in_weight_i s_i -
weighted_sum_i`` (Li2020 eq. (24)). ``c_ij > 0``: i receives from j (row i = receiver). Messages have
shape (N, d). With delays: ``delayed-graph`` (:mod:`formation_ftc.components.networks.delayed_graph`).
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np
from pydantic import Field, model_validator

from formation_ftc.components._registry import BuildContext, register
from formation_ftc.config.base import StrictModel
from formation_ftc.core.graph import GraphError, validate_adjacency
from formation_ftc.sim.components import Network, NetworkInputs, component
from formation_ftc.sim.contract import as_float

__all__ = ["GraphNetwork", "GraphSection", "graph_edges"]


def graph_edges(weights) -> tuple[tuple[int, int], ...]:
    """Used links (i, j) (0-based receiver, sender) of a weight matrix, row-major order.

    Parameters
    ----------
    weights : array_like, shape (N, N)
        Link weights c_ij, row i = receiver [-]; a link is used where c_ij > 0.

    Returns
    -------
    tuple of tuple of int
        ``(i, j)`` pairs.

    Examples
    --------
    >>> from formation_ftc.components.networks.graph import graph_edges
    >>> graph_edges([[0.0, 1.0, 0.0], [0.5, 0.0, 2.0], [0.0, 0.0, 0.0]])
    ((0, 1), (1, 0), (1, 2))
    """
    w = np.asarray(weights, dtype=float)
    return tuple((int(i), int(j)) for i, j in zip(*np.nonzero(w > 0), strict=True))


@component
class GraphNetwork(Network):
    """Instantaneous exchange over a weighted directed graph ``adjacency`` (N, N) [-]."""

    adjacency: Any  # (N, N) c_ij, row i = receiver

    @property
    def count(self) -> int:
        return int(np.shape(self.adjacency)[0])

    def receive(self, t, state, inputs: NetworkInputs):
        C, m = self.adjacency, inputs.messages
        # sum_j c_ij m_j as N broadcast multiply-adds (elementwise, fuses with its consumers; a
        # dot_general is a separate XLA kernel with a transpose around it under vmap)
        weighted = sum(C[:, j, None] * m[..., j, None, :] for j in range(self.count))
        return {"in_weight": jnp.sum(C, axis=1), "weighted_sum": weighted}


class GraphSection(StrictModel):
    """The weighted directed graph: ``adjacency[i][j] = c_ij > 0`` when spacecraft i receives from j."""

    adjacency: list[list[float]] = Field(
        description="c_ij >= 0: spacecraft i receives from j (N x N) [-]."
    )

    @model_validator(mode="after")
    def _square(self):
        if len({len(r) for r in self.adjacency} | {len(self.adjacency)}) != 1:
            raise ValueError("adjacency: must be square (N x N)")
        try:  # finite, >= 0, no self-loops
            validate_adjacency(self.adjacency, field="adjacency")
        except GraphError as exc:
            raise ValueError(str(exc)) from None
        return self


def _build(sec: GraphSection, ctx: BuildContext) -> GraphNetwork:
    """The network of a validated ``[network] type = "graph"`` section."""
    return GraphNetwork(adjacency=as_float(validate_adjacency(sec.adjacency, ctx.count)))


register(
    "network",
    "graph",
    GraphSection,
    _build,
    "instantaneous exchange over a weighted directed graph",
)
