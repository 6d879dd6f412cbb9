import numpy as np
import pytest

from formation_ftc.core import graph

C_LI = np.array([[0, 0, 0.5, 0], [0.6, 0, 0, 0], [0, 0.5, 0, 0.4], [0.6, 0, 0, 0]])


def test_li2020_graph_not_balanced():
    # SPEC.md P0.6-1: row sums [0.5, 0.6, 0.9, 0.6], column sums [1.2, 0.5, 0.5, 0.4]
    rep = graph.balance_report(C_LI)
    assert not rep.balanced
    np.testing.assert_allclose(rep.row_sums, [0.5, 0.6, 0.9, 0.6])
    np.testing.assert_allclose(rep.column_sums, [1.2, 0.5, 0.5, 0.4])
    assert "NOT balanced" in str(rep)
    assert graph.is_strongly_connected(C_LI)


def test_balanced_variant():
    C = np.array([[0, 0, 0.9, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0.4], [0.4, 0, 0, 0]])
    assert graph.is_balanced(C) and graph.is_strongly_connected(C)


def test_laplacian_rows_sum_to_zero_and_neighbours():
    L = graph.laplacian(C_LI)
    np.testing.assert_allclose(L.sum(axis=1), 0, atol=1e-15)
    assert graph.neighbours(C_LI, 2) == [1, 3]


def test_not_strongly_connected():
    C = np.array([[0, 1.0, 0], [0, 0, 0], [0, 0, 0]])
    assert not graph.is_strongly_connected(C)


def test_undirected_ring():
    C = graph.adjacency(4, [(0, 1), (1, 2), (2, 3), (3, 0)], directed=False)
    assert graph.is_connected_undirected(C)
    np.testing.assert_allclose(graph.row_normalized(C).sum(axis=1), 1.0)


@pytest.mark.parametrize(
    "C,msg",
    [
        (np.ones((2, 3)), "square"),
        (np.array([[0, -1.0], [1, 0]]), ">= 0"),
        (np.array([[1.0, 0], [1, 0]]), "self-loops"),
        (np.array([[0, np.nan], [1, 0]]), "finite"),
    ],
)
def test_bad_adjacency(C, msg):
    with pytest.raises(graph.GraphError, match=msg):
        graph.validate_adjacency(C)


def test_wrong_size():
    with pytest.raises(graph.GraphError, match="must be 4x4"):
        graph.validate_adjacency(np.zeros((3, 3)), n=4)
