"""Every theorem/design condition says how its verdict was obtained (exact, verified bound, sampled, or
heuristic) and definiteness claims clear a rounding margin.

Truth for the margin test: a symmetric matrix whose largest eigenvalue lies inside the floating-point
error of the eigenvalue solver must not count as negative definite.
"""

import numpy as np
import pytest

from formation_ftc import api
from formation_ftc.design.lmi import rounding_margin

#: conditions registered by papers/*/registration.py on their laws are listed by paper
OWN = ("gui2022", "li2020", "mehrabian", "yang2013")
WORDS = (
    "exact",
    "verified",
    "certified",
    "sampled",
    "heuristic",
    "residual",
    "eigenvalues",
    "informative",
    "not applicable",
    "untestable",
)


@pytest.mark.parametrize("name", sorted(n for n in api.list_scenarios() if n.split("-")[0] in OWN))
def test_every_condition_that_holds_states_how(name):
    for c in api.check(name):
        if c.holds:
            assert any(w in c.detail.lower() for w in WORDS), (name, c.name, c.detail)


def test_rounding_margin_rejects_a_marginal_negative_eigenvalue():
    rng = np.random.default_rng(3)
    Q, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    lam = np.array(
        [-1e6, -3e5, -1.0, -2.0, -5.0, -1e-12]
    )  # the last one is below the rounding level
    M = Q @ np.diag(lam) @ Q.T
    M = (M + M.T) / 2
    tol = rounding_margin(M)
    assert tol > 1e-12
    assert not np.linalg.eigvalsh(M).max() < -tol  # not verified
    M2 = Q @ np.diag(np.r_[lam[:5], -1e-3]) @ Q.T
    assert np.linalg.eigvalsh((M2 + M2.T) / 2).max() < -rounding_margin(M2)  # verified
