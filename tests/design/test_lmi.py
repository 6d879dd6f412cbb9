"""ILO gain LMIs (Gui2022 (8), (27), disk S(-5, 2)): certificates, homogeneity, printed gains, infeasibility.

Truths: the numerical residual certificate (eigenvalues of each LMI block computed independently with
numpy), the eigenvalues of A - L1 C, and the printed-gain facts of E002-06 / SPEC P2.6 #2.
"""

import numpy as np
import pytest

from formation_ftc.core.dynamics.cw import cw_matrices
from formation_ftc.design.lmi import (
    DesignInfeasible,
    design_ilo_gains,
    ilo_lmi_residuals,
    rescale_design,
)
from formation_ftc.papers.gui2022 import published as pub

A, B = cw_matrices(pub.N_MEAN_MOTION)
C = np.eye(6)


@pytest.fixture(scope="module")
def design():
    return design_ilo_gains(A, C, B, lam=1e-8, disk_center=-5.0, disk_radius=2.0)


def test_design_satisfies_every_lmi(design):
    r = design.residuals
    assert design.status == "optimal"
    assert r["max_eig_8"] < -1e-6 and r["max_eig_disk"] < -1e-6 and r["max_eig_27"] < 0
    assert r["min_eig_P"] >= 1 - 1e-6  # normalisation P >= I
    assert r["max_abs_9"] <= 1e-4  # (27) <=> ||H^T P - L2 C||_2 < sqrt(lam) = 1e-4
    np.testing.assert_allclose(design.P @ design.L1, design.Y, atol=1e-9)  # L1 = P^-1 Y
    poles = np.linalg.eigvals(A - design.L1 @ C)
    assert np.max(np.abs(poles + 5.0)) < 2.0  # inside S(-5, 2)
    # same structure as the printed L1: identity kinematic coupling, +-2n-like Coriolis terms
    assert design.L1[0, 3] == pytest.approx(1.0, abs=0.02)
    assert abs(design.L1[3, 4]) == pytest.approx(0.003, abs=2e-4)


def test_homogeneity_rescaling_keeps_feasibility_and_L1(design):
    big = rescale_design(design, 456.271, A, C, B)
    np.testing.assert_allclose(big.L1, design.L1, atol=1e-12)
    assert big.L2[0, 3] == pytest.approx(456.271 * design.L2[0, 3])
    assert big.residuals["max_eig_8"] < 0 and big.residuals["max_eig_disk"] < 0
    assert big.residuals["max_eig_8"] == pytest.approx(
        456.271 * design.residuals["max_eig_8"], rel=1e-9
    )


def test_printed_gains_facts():
    # SPEC P2.6 #2 / E002-06
    poles = np.sort(np.linalg.eigvals(A - pub.L1_PRINTED).real)
    np.testing.assert_allclose(poles, [-4.5471] * 5 + [-4.5470], atol=6e-5)
    assert np.max(np.abs(np.linalg.eigvals(A - pub.L1_PRINTED) + 5)) == pytest.approx(
        0.453, abs=1e-3
    )
    P = np.diag([1, 1, 1, *np.diag(pub.L2_PRINTED[:, 3:])])
    r = ilo_lmi_residuals(A, C, B, P, P @ pub.L1_PRINTED, pub.L2_PRINTED)
    assert r["max_eig_8"] == pytest.approx(-9.09, abs=0.01)
    assert r["max_abs_9"] == 0.0  # (9) exactly
    assert r["max_pole_distance"] < 2


def test_infeasible_region_names_constraint_and_status():
    # a disk in the right half plane contradicts the Lyapunov inequality (8)
    with pytest.raises(DesignInfeasible) as exc:
        design_ilo_gains(A, C, B, disk_center=5.0, disk_radius=2.0)
    msg = str(exc.value)
    assert "infeasible" in exc.value.status
    assert "status 'infeasible" in msg and "disk pole region S(5, 2)" in msg and "(8)" in msg
    assert set(exc.value.constraints) == {"lyapunov_8", "disk"}
    assert isinstance(exc.value, ValueError)  # the CLI reports it as bad input, no traceback


def test_bad_arguments():
    with pytest.raises(ValueError, match="disk_radius"):
        design_ilo_gains(A, C, B, disk_radius=0.0)
    with pytest.raises(ValueError, match="lam"):
        design_ilo_gains(A, C, B, lam=-1.0)
