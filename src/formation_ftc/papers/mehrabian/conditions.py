"""Gain conditions (9)-(11) and the derived design quantities R_j (13), sum Q_jn (14), Q_j (15), P_j (21)
of Mehrabian et al., printed next to the paper's values (E003-02, E003-03, E003-05). Pure numpy.

:func:`check` is registered for every composed loop with ``controller.type = "networked-el-hinf"``: the
conditions are on the law's gains, its graph, its model inertia J^ and the step, so they apply on any
plant the law composes with (the Euler-angle plant, or a quaternion plant seen through the Euler
sensors and the equal-power torque allocation: the same Euler-Lagrange system (1)).
:func:`fdi_check` is registered for every loop with ``estimator.type = "attitude-residual-fdi"``, the
detected FDI that reports to that law: its model of the command over a step against the law's sampling.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from formation_ftc.components.controllers.networked_el_hinf import modal_damping
from formation_ftc.core import graph as graphs
from formation_ftc.design.lmi import rounding_margin
from formation_ftc.papers._conditions import exact, fmt_list
from formation_ftc.registry import Condition

__all__ = [
    "PRINTED",
    "PRINTED_RESOLUTION",
    "matches_printed",
    "DesignQuantities",
    "design_quantities",
    "lyapunov_matrix",
    "check",
    "fdi_check",
]

#: Values printed in Sec. V (per channel; the paper repeats each three times).
PRINTED: dict[str, Any] = {  # a number or a diagonal (3 numbers) per quantity
    "R": 17.22,
    "sum_Q_jn": (0.17e-4, 0.44, 17.22),
    "Q_j": (0.27e-5, 0.031e-3, 2.78),
}


@dataclass(frozen=True)
class DesignQuantities:
    """Per-channel (scalar-gain) design quantities."""

    K_minus: float  # K - 1/gamma^2 [N m s]
    R: float  # (13) R_j = (K - 1/gamma^2)^-1
    sum_Q_jn: tuple[float, float, float]  # (14) alpha diag(K_I^2 K, K_P^2 K, K)
    Q_j: tuple[float, float, float]  # (15) (1 - alpha) diag(...) - diag(0, 2 K_I K, 0)
    cond11: float  # (1 - alpha) K_P^2 - 2 K_I
    cond11_swapped: float  # the same with K_P and K_I exchanged (E003-03)
    consensus_damping_literal: float  # 1/2 [(1 - alpha) K - 1/gamma^2]
    alpha_limit: float  # 1 - 1/(K gamma^2): literal law needs alpha below it


def design_quantities(
    K: float, K_P: float, K_I: float, alpha: float, gamma: float
) -> DesignQuantities:
    """Mehrabian (13)-(15) with K-bar = K_P (proportional), K-double-bar = K_I (integral), E003-03."""
    km = K - 1.0 / gamma**2
    base = np.array([K_I**2 * K, K_P**2 * K, K])
    sum_q = alpha * base  # (14)
    q_j = (1.0 - alpha) * base - np.array([0.0, 2.0 * K_I * K, 0.0])  # (15), -2 K_I K per E003-03
    return DesignQuantities(
        K_minus=km,
        R=1.0 / km if km != 0 else float("inf"),
        sum_Q_jn=(float(sum_q[0]), float(sum_q[1]), float(sum_q[2])),
        Q_j=(float(q_j[0]), float(q_j[1]), float(q_j[2])),
        cond11=(1.0 - alpha) * K_P**2 - 2.0 * K_I,
        cond11_swapped=(1.0 - alpha) * K_I**2 - 2.0 * K_P,
        consensus_damping_literal=float(modal_damping(K, alpha, gamma, 1.0, "literal")),
        alpha_limit=1.0 - 1.0 / (K * gamma**2),
    )


def lyapunov_matrix(D: np.ndarray, K: float, K_P: float, K_I: float) -> np.ndarray:
    """Reconstructed (21): P = [K_I; K_P; I] D [K_I, K_P, I] + blkdiag([[K_I K_P K, K_I K], [K_I K, K_P K]], 0).

    ``D`` is (n, n); returns (3n, 3n) for x = [int q~, q~, q~_dot]."""
    n = D.shape[0]
    I = np.eye(n)
    V = np.hstack([K_I * I, K_P * I, I])
    P = V.T @ D @ V
    P[: 2 * n, : 2 * n] += np.kron([[K_I * K_P * K, K_I * K], [K_I * K, K_P * K]], I)
    return P


#: Resolution of the printed digits (the paper truncates: 2.78e-6 is printed 0.27e-5).
PRINTED_RESOLUTION = {"sum_Q_jn": (1e-6, 0.01, 0.01), "Q_j": (1e-7, 1e-6, 0.01)}


def matches_printed(values, printed, resolution) -> list[bool]:
    """Per entry: ``value`` truncated to the printed resolution equals the printed number."""
    return [
        bool(abs(np.trunc(v / r + 1e-9) * r - p) < 1e-3 * r)
        for v, p, r in zip(values, printed, resolution, strict=True)
    ]


#: Reference of the gain conditions (9).
REF_9 = "Mehrabian (9), E003-03"
#: Details of the exact scalar conditions.
SCALAR = "exact: scalar comparison of the scenario values"
ARITHMETIC = "exact: scalar arithmetic on the scenario values"


def check(s: Any, loop: Any) -> list[Condition]:
    """Conditions (9)-(11), the literal law's consensus-mode damping, P_j > 0, graph, derived values.

    Parameters
    ----------
    s : ComposedScenario
        A composed scenario whose controller is ``networked-el-hinf``.
    loop : ClosedLoop
        Its built loop (the spacecraft count is the plant's).

    Returns
    -------
    list of Condition
        Gains, graph and design quantities with the paper's printed values [SI].
    """
    c = s.section("controller")
    K, KP, KI, a, g = c.K, c.K_P, c.K_I, c.alpha, c.gamma
    dq = design_quantities(K, KP, KI, a, g)
    out = [
        exact("K-bar > 0 (proportional gain)", REF_9, f"K_P = {KP:.4g}", "> 0", KP > 0, SCALAR),
        exact("K-double-bar > 0 (integral gain)", REF_9, f"K_I = {KI:.4g}", "> 0", KI > 0, SCALAR),
        exact(
            "K - I/gamma^2 > 0",
            "Mehrabian (9)",
            f"{K:.4g} - 1/{g:.4g}^2 = {dq.K_minus:.6g}",
            "> 0",
            dq.K_minus > 0,
            "exact: scalar arithmetic on the scenario values (float64; the sign is decided "
            "unless K gamma^2 = 1 to within 1e-16)",
        ),
        exact(
            "0 < alpha < 1",
            "Mehrabian (10)",
            f"alpha = {a:.4g}",
            "0 < alpha < 1",
            0 < a < 1,
            SCALAR,
        ),
        exact(
            "(1 - alpha) K-bar^2 - 2 K-double-bar > 0",
            "Mehrabian (11), E003-03",
            f"(1 - {a:.4g}) {KP:.4g}^2 - 2 {KI:.4g} = {dq.cond11:.6g}",
            "> 0",
            dq.cond11 > 0,
            f"exact: scalar arithmetic; with the gain letters swapped (K-bar = {KI:g}): "
            f"{dq.cond11_swapped:.4g} (E003-03)",
        ),
    ]
    if c.law == "literal":
        out.append(
            exact(
                "consensus-mode damping of the literal law",
                "Mehrabian (8) first line, E003-01",
                f"1/2[(1 - alpha) K - 1/gamma^2] = {dq.consensus_damping_literal:.6g} N m s",
                f"> 0 (alpha < 1 - 1/(K gamma^2) = {dq.alpha_limit:.6g})",
                dq.consensus_damping_literal > 0,
                ARITHMETIC,
            )
        )
    else:
        out.append(
            exact(
                "consensus-mode damping of the diffusive law",
                "E003-01 alternative",
                f"1/2 (K - 1/gamma^2) = {0.5 * dq.K_minus:.6g} N m s",
                "> 0",
                dq.K_minus > 0,
                ARITHMETIC,
            )
        )
    Jn = np.diag(c.nominal_inertia)  # the law's model J^ (stated on board)
    Ps = [lyapunov_matrix(D, K, KP, KI) for D in (Jn, 10 * np.eye(3), 20 * np.eye(3))]
    eigs = [np.linalg.eigvalsh(P).min() for P in Ps]
    tol = max(rounding_margin(P) for P in Ps)
    m = loop.plant.count
    A = graphs.adjacency(m, [(a - 1, b - 1) for a, b in c.edges], directed=False)
    lam = np.sort(np.linalg.eigvalsh(graphs.laplacian(A)))
    # derived design quantities next to the printed ones (informational)
    dq861 = design_quantities(K, KP, KI, 0.861, g)
    out += [
        exact(
            "P_j positive definite",
            "Mehrabian (21) (reconstructed)",
            f"min eig = {eigs[0]:.4g} (D = J^), {eigs[1]:.4g} (D = 10 I), {eigs[2]:.4g} (D = 20 I)",
            "> 0 (iff K_P > K_I for scalar gains)",
            bool(min(eigs) > tol),
            f"exact up to rounding: symmetric eigenvalues (numpy) clear the rounding margin {tol:.2g} "
            "(10 n eps ||P||)",
            required=False,
        ),
        exact(
            "communication graph connected",
            "Mehrabian Sec. II-B",
            f"lambda_2(L) = {lam[1]:.4g}",
            "> 1e-9 (rounding margin)",
            bool(lam[1] > 1e-9),
            "exact up to rounding: symmetric eigenvalues of the Laplacian (numpy, error "
            "<= 10 n eps ||L||, far below the 1e-9 margin)",
        ),
        exact(
            "R_j",
            "Mehrabian (13), E003-02",
            f"{dq.R:.6g} I3 (its inverse K - I/gamma^2 = {dq.K_minus:.6g})",
            f"paper prints {PRINTED['R']} I3, which is R_j^-1",
            abs(dq.K_minus - PRINTED["R"]) < 5e-3,
            "informative (exact arithmetic): 17.22 equals K - I/gamma^2 = R_j^-1, not R_j (E003-02)",
            required=False,
        ),
        exact(
            "sum_n Q_jn",
            "Mehrabian (14), E003-05",
            f"diag {fmt_list(dq.sum_Q_jn)} (alpha = {a:g}); {fmt_list(dq861.sum_Q_jn)} (alpha = 0.861)",
            f"paper prints diag {fmt_list(PRINTED['sum_Q_jn'])}",
            all(
                matches_printed(dq861.sum_Q_jn, PRINTED["sum_Q_jn"], PRINTED_RESOLUTION["sum_Q_jn"])
            ),
            "informative (exact arithmetic): alpha = 0.861 reproduces the printed (truncated) "
            "digits (E003-05)",
            required=False,
        ),
        exact(
            "Q_j",
            "Mehrabian (15), E003-05",
            f"diag {fmt_list(dq.Q_j)} (alpha = {a:g}); {fmt_list(dq861.Q_j)} (alpha = 0.861)",
            f"paper prints diag {fmt_list(PRINTED['Q_j'])}; > 0 needed",
            bool(min(dq.Q_j) > 0),
            "exact: scalar arithmetic; the printed middle entry 0.031e-3 must read 0.031 (E003-05)",
            required=False,
        ),
    ]
    # RK4 step against the fastest closed-loop rate (sat boundary layer and coupling)
    mu_min = float(np.min(np.linalg.eigvals(graphs.row_normalized(A)).real))
    damp = max(modal_damping(K, a, g, mu, c.law) for mu in (mu_min, 1.0))
    u_hat_ref = 1.0  # N m: order of the fault estimate, sets the sat slope u^/phi_b
    rate = (damp + (u_hat_ref / c.boundary_layer if c.compensation == "sat" else 0.0)) / min(
        c.nominal_inertia
    )
    h = s.simulation.dt * rate
    over = bool(h >= 2.78)
    out.append(
        Condition(
            "RK4 step vs fastest rate",
            "dt * (max modal damping + 1 N m/phi_b) / min J",
            f"{h:.3g}",
            "< 2.78 (RK4 real-axis stability limit)",
            False if over else None,
            required=False,
            basis="heuristic",
            detail="heuristic: the fastest rate is estimated from the modal damping and an assumed "
            "1 N m fault estimate in the sat boundary layer (not a bound on the closed-loop "
            "eigenvalues of the nonlinear loop); "
            + (
                "the estimate exceeds the limit: a warning, not a proof"
                if over
                else "below the limit, which proves nothing (unproven)"
            ),
        )
    )
    return out


def fdi_check(s: Any, loop: Any) -> list[Condition]:
    """The attitude residual FDI's model of the command over a step against the law's sampling.

    Parameters
    ----------
    s : ComposedScenario
        A scenario with ``[estimator] type = "attitude-residual-fdi"``.
    loop : ClosedLoop
        Its loop.

    Returns
    -------
    list of Condition
        One condition (not required).
    """
    sec = s.section("estimator")
    sampled = bool(loop.controller.sampled)
    fits = sampled == (sec.command == "held")
    return [
        exact(
            "attitude FDI: command model over each step",
            "docs/concepts/navigation-and-fdi.md",
            f"command = {sec.command}; controller {s.labels()['controller']} "
            + ("is sampled" if sampled else "is evaluated inside the step"),
            "held for a sampled law, extrapolated for a law evaluated inside the step",
            fits,
            "exact: held is the exact mean of a sampled command; for a law evaluated at every "
            "integrator stage the extrapolation 1.5 tau_k - 0.5 tau_k-1 removes the first-order "
            "error (attitude league, Mehrabian, 0.05 s: largest |r| without fault 2.3e-4 N m, "
            "against 8e-3 N m with the command held)",
            required=False,
        )
    ]
