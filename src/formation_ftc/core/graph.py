"""Communication-graph utilities (networkx underneath).

Convention: **row i = receiver**, ``C[i, j] > 0`` means agent i receives from agent j.
In-weight = row sums, out-weight = column sums, Laplacian ``L = diag(rowsum) - C``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # networkx is slow to import: the functions that use it import it (issue 37)
    import networkx as nx

__all__ = [
    "GraphError",
    "validate_adjacency",
    "adjacency",
    "laplacian",
    "in_degree",
    "out_degree",
    "is_balanced",
    "balance_report",
    "is_strongly_connected",
    "is_connected_undirected",
    "neighbours",
    "row_normalized",
    "to_networkx",
]


class GraphError(ValueError):
    """Invalid adjacency matrix."""


def validate_adjacency(C, n: int | None = None, field: str = "network.adjacency") -> np.ndarray:
    """Return ``C`` as a float array after checking shape, finiteness, sign and self-loops.

    Raises :class:`GraphError` naming ``field`` and the offending entry.
    """
    A = np.asarray(C, dtype=float)
    if A.ndim != 2 or A.shape[0] != A.shape[1]:
        raise GraphError(f"{field}: must be a square matrix, got shape {A.shape}")
    if n is not None and A.shape[0] != n:
        raise GraphError(
            f"{field}: must be {n}x{n} (one row/column per spacecraft), got {A.shape[0]}x{A.shape[1]}"
        )
    if not np.all(np.isfinite(A)):
        raise GraphError(f"{field}: entries must be finite")
    neg = np.argwhere(A < 0)
    if neg.size:
        i, j = neg[0]
        raise GraphError(f"{field}[{i}][{j}] = {A[i, j]}: weights must be >= 0")
    diag = np.flatnonzero(np.diag(A) != 0)
    if diag.size:
        i = diag[0]
        raise GraphError(
            f"{field}[{i}][{i}] = {A[i, i]}: self-loops are not allowed (diagonal must be 0)"
        )
    return A


def adjacency(
    n: int, edges: list[tuple[int, int]], weights: list[float] | None = None, directed: bool = True
) -> np.ndarray:
    """Build an adjacency matrix from (receiver, sender) pairs (0-based)."""
    A = np.zeros((n, n))
    w = weights if weights is not None else [1.0] * len(edges)
    for (i, j), wij in zip(edges, w, strict=True):
        A[i, j] = wij
        if not directed:
            A[j, i] = wij
    return validate_adjacency(A, n)


def in_degree(C) -> np.ndarray:
    """Row sums (weighted in-degree of each receiver)."""
    return np.asarray(C, dtype=float).sum(axis=1)


def out_degree(C) -> np.ndarray:
    """Column sums (weighted out-degree of each sender)."""
    return np.asarray(C, dtype=float).sum(axis=0)


def laplacian(C) -> np.ndarray:
    """L = diag(row sums) - C."""
    return np.diag(in_degree(C)) - np.asarray(C, dtype=float)


def is_balanced(C, tol: float = 1e-12) -> bool:
    """True when every node's in-weight equals its out-weight."""
    return bool(np.max(np.abs(in_degree(C) - out_degree(C))) <= tol)


@dataclass(frozen=True)
class BalanceReport:
    balanced: bool
    row_sums: tuple[float, ...]
    column_sums: tuple[float, ...]

    def __str__(self) -> str:
        rs = ", ".join(f"{v:g}" for v in self.row_sums)
        cs = ", ".join(f"{v:g}" for v in self.column_sums)
        word = "balanced" if self.balanced else "NOT balanced"
        return f"{word}: row sums [{rs}], column sums [{cs}]"


def balance_report(C, tol: float = 1e-12) -> BalanceReport:
    """Balance verdict with the row (in) and column (out) sums."""
    return BalanceReport(
        is_balanced(C, tol), tuple(map(float, in_degree(C))), tuple(map(float, out_degree(C)))
    )


def to_networkx(C) -> nx.DiGraph:
    """Directed graph with an edge j -> i for every C[i, j] > 0 (information flows sender -> receiver)."""
    import networkx as nx

    A = np.asarray(C, dtype=float)
    G = nx.DiGraph()
    G.add_nodes_from(range(A.shape[0]))
    for i, j in zip(*np.nonzero(A), strict=True):
        G.add_edge(int(j), int(i), weight=float(A[i, j]))
    return G


def is_strongly_connected(C) -> bool:
    import networkx as nx

    return bool(nx.is_strongly_connected(to_networkx(C)))


def is_connected_undirected(C) -> bool:
    """True when C is symmetric and its graph is connected."""
    import networkx as nx

    A = np.asarray(C, dtype=float)
    return bool(np.allclose(A, A.T) and nx.is_connected(to_networkx(A).to_undirected()))


def neighbours(C, i: int) -> list[int]:
    """Agents that i receives from."""
    return [int(j) for j in np.flatnonzero(np.asarray(C)[i] > 0)]


def row_normalized(C) -> np.ndarray:
    """D_deg^-1 C (rows with no neighbour stay zero)."""
    A = np.asarray(C, dtype=float)
    d = A.sum(axis=1)
    return np.divide(A, d[:, None], out=np.zeros_like(A), where=d[:, None] > 0)
