"""Component-wise 3-vector helpers against numpy's reductions (1e-15 relative: only the summation
order differs)."""

from __future__ import annotations

import numpy as np

from formation_ftc.core.vector3 import dot3, norm3, sq_norm3


def test_against_numpy_reductions():
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(5, 4, 3)), rng.normal(size=(5, 4, 3))
    np.testing.assert_allclose(dot3(a, b), np.einsum("...k,...k->...", a, b), rtol=1e-14)
    np.testing.assert_allclose(sq_norm3(a), np.sum(a**2, axis=-1), rtol=1e-14)
    np.testing.assert_allclose(norm3(a), np.linalg.norm(a, axis=-1), rtol=1e-14)
    assert norm3(np.array([3.0, 4.0, 12.0])) == 13.0
