"""Communication faults on a weighted graph: links lost after an onset, delays scaled after it.

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

from formation_ftc.components.networks.delayed_graph import DelayedGraphNetwork
from formation_ftc.components.networks.graph import GraphNetwork
from formation_ftc.sim.components import NetworkInputs, component

__all__ = ["GraphLinkLossNetwork", "DelayedGraphLinkLossNetwork", "faulty_weights"]


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
    >>> from formation_ftc.components.networks.link_faults import faulty_weights
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
        w = faulty_weights(self.adjacency, self.lost, self.onset, inputs.t_k)
        return GraphNetwork.receive(dataclasses.replace(self, adjacency=w), t, state, inputs)


@component
class DelayedGraphLinkLossNetwork(DelayedGraphNetwork):
    """:class:`DelayedGraphNetwork` whose links marked in ``lost`` (N, N) [-] stop delivering and whose
    delays are multiplied by ``delay_scale`` [-] from ``onset`` [s] on."""

    lost: Any = 0.0  # (N, N) [-]
    onset: Any = float("inf")  # [s]
    delay_scale: Any = 1.0  # [-]

    def receive(self, t, state, inputs: NetworkInputs):
        after = inputs.t_k >= self.onset
        w = faulty_weights(self.adjacency, self.lost, self.onset, inputs.t_k)
        T = inputs.exogenous["T"] * jnp.where(after, self.delay_scale, 1.0)
        return DelayedGraphNetwork.receive(
            dataclasses.replace(self, adjacency=w),
            t,
            state,
            inputs._replace(exogenous={**inputs.exogenous, "T": T}),
        )
