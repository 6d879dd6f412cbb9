"""Design conditions of Azizi & Khorasani 2009 for composed scenarios of its law (``formation-ftc
check`` of a ``controller.type = "azizi2009-llfr"`` loop on the deep-space ``double-integrator``
plant; registered by the paper's package, see :mod:`.registration`).

Loop -> numbers: the weights, the LLFR estimate b_hat and the FLFR weight of the law (flight side),
the true faulty gains of the actuator (truth side), the FLFR design of eqs. (8)-(11)
(:func:`formation_ftc.components.controllers.azizi2009_llfr.flfr_design`, cached) and ||D||_2 of eq. (6).

Conditions, all from Azizi & Khorasani 2009:

* allocation inputs valid (alpha_i > 0, b_hat_i > 0; eq. (3));
* Lemma 1 / E004-03: DET = q2 alpha_2 + q1 > 0 and equal to -det(J_aug);
* Theorem 1 (small gain): ||Delta||_2 < B_Delta = 1 / gamma_1 for the LLFR and the FLFR weights;
* B_eps covers the actual estimation error |b_hat - b| (informational: it uses the true b);
* Theorem 2 / eq. (11): the FLFR design is feasible (e_s above the disturbance floor T_i) and the
  bound (8) at the FLFR weight is <= e_s.

Bases (:class:`formation_ftc.registry.Condition`): scalar and determinant conditions are exact; the small
gain and the floor are *verified* (gamma_1 and T_i are certified upper bounds of H-infinity norms,
:func:`formation_ftc.design.small_gain.hinf_norm`); the bound (8) is *sampled*: H_i is the supremum of a
simulated response over 300 s (RK4), not a bound, so a pass is reported unproven. Other plants (the
law flying orbital relative motion) are outside the theorems: no conditions.
"""

from __future__ import annotations

import numpy as np

from formation_ftc.components.actuators.actuator_gains import StepGainActuator
from formation_ftc.components.controllers.azizi2009_llfr import (
    AXES,
    ChainLlfrController,
    flfr_design,
)
from formation_ftc.components.plants.double_integrator import DoubleIntegratorPlant
from formation_ftc.components.supervisors.hierarchical import HierarchicalSupervisor
from formation_ftc.design.allocation import augmented_matrix_np, perturbation_coefficients
from formation_ftc.design.flfr import error_dynamics_matrix, reduced_model
from formation_ftc.design.small_gain import small_gain_margin
from formation_ftc.methods.composed import ComposedScenario
from formation_ftc.papers._conditions import exact, informative
from formation_ftc.registry import Condition
from formation_ftc.sim.loop import ClosedLoop

__all__ = ["conditions", "perturbation_norm", "d_norms", "true_gains"]


def true_gains(loop: ClosedLoop) -> np.ndarray | None:
    """True actuator gains after the fault (N, axes) [-] (truth side; None: not a gain actuator)."""
    act = loop.actuator
    return np.asarray(act.faulty_gain, float) if isinstance(act, StepGainActuator) else None


def _chain_law(loop: ClosedLoop) -> ChainLlfrController:
    """The loop's controller, the law itself (the double integrators are driven by accelerations)."""
    law = loop.controller
    if not isinstance(law, ChainLlfrController):
        raise TypeError(f"controller {type(law).__name__} is not the Azizi2009 chain law")
    return law


def perturbation_norm(alpha, b_hat, k: int, eps: float) -> float:
    """||D||_2 with D = E J_aug(alpha, b_hat)^-1 of eq. (6) for an estimation error eps on satellite k
    (0-based; E[k-1, k] = -eps, E[k, k] = +eps, the rows that exist) [-]."""
    alpha, b_hat = np.asarray(alpha, float), np.asarray(b_hat, float)
    n = alpha.size
    E = np.zeros((n - 1, n))
    if k > 0:
        E[k - 1, k] = -eps
    if k < n - 1:
        E[k, k] = eps
    rows = np.arange(n - 1)
    J_aug = np.zeros((n, n))  # eq. (3): chain rows of eq. (2), then alpha_i / b_hat_i (E004-02)
    J_aug[rows, rows] = -b_hat[:-1]
    J_aug[rows, rows + 1] = b_hat[1:]
    J_aug[n - 1] = alpha / b_hat
    return float(np.linalg.norm(E @ np.linalg.inv(J_aug), 2))


def d_norms(
    scenario: ComposedScenario, loop: ClosedLoop, alpha, a_flfr: float
) -> tuple[float, float]:
    """||D||_2 at the LLFR weights ``alpha`` and with the FLFR weight ``a_flfr`` of the law's faulty
    spacecraft, with the true eps of the loop's actuator on the faulty axis."""
    ax = AXES.index(scenario.section("controller").faulty_axis)
    law = _chain_law(loop)
    k = law.fault_index
    b_hat = np.asarray(law.b_hat, float)[:, ax]
    gains = true_gains(loop)
    if gains is None:
        raise ValueError("||D||_2 needs the true gains of an actuator-gains actuator")
    eps = float(b_hat[k] - gains[k, ax])
    alpha = np.asarray(alpha, float)
    alpha_f = alpha.copy()
    alpha_f[k] = a_flfr
    return perturbation_norm(alpha, b_hat, k, eps), perturbation_norm(alpha_f, b_hat, k, eps)


def conditions(scenario: ComposedScenario, loop: ClosedLoop) -> list[Condition]:
    """The paper's design conditions for a loop of its law (see module docstring); [] off the
    deep-space plant."""
    if not isinstance(loop.plant, DoubleIntegratorPlant):
        return []
    c = scenario.section("controller")
    law = _chain_law(loop)
    hierarchical = isinstance(loop.supervisor, HierarchicalSupervisor)
    sup = scenario.section("supervisor") if hierarchical else None
    flfr = sup is not None and sup.flfr
    alpha = np.asarray(law.alpha, float)
    n = alpha.size
    out = [
        exact(
            "allocation weights",
            "Azizi2009 eq. (3)",
            f"alpha = {alpha.tolist()}",
            "alpha_i > 0",
            bool(np.all(alpha > 0)),
            detail="exact: comparison of the scenario values",
        )
    ]
    if c.faulty_spacecraft is None:
        out.append(
            exact(
                "fault-free allocation",
                "Azizi2009 eq. (4)",
                "b_hat = b",
                "exact cancellation: e'' = -l1 e' - l0 e",
                True,
                required=False,
                detail="exact: without a fault the estimate equals the true gain by construction",
            )
        )
        return out
    k = c.faulty_spacecraft - 1
    ax = AXES.index(c.faulty_axis)
    b_hat = np.asarray(law.b_hat, float)[:, ax]
    gains = true_gains(loop)
    if gains is not None:
        eps = float(b_hat[k] - gains[k, ax])
        out.append(
            exact(
                "estimation error within B_eps",
                "Azizi2009 Sec. IV, |eps| < B_eps",
                f"|eps| = {abs(eps):.4g}, B_eps = {c.b_eps:.4g}",
                "|b_hat - b| <= B_eps",
                abs(eps) <= c.b_eps + 1e-12,
                required=False,
                detail="exact (tolerance 1e-12): uses the true gain (truth side); the design only "
                "knows B_eps",
            )
        )
    if not 0 < k < n - 1:
        out.append(
            informative(
                "interior faulty satellite",
                "Azizi2009 eq. (6)-(7)",
                f"satellite {k + 1}",
                f"2..{n - 1} for the reduced model (7)",
                None,
                "informative: the reduced model (7) and its conditions need an interior "
                "satellite; not evaluated",
            )
        )
        return out
    coeff = perturbation_coefficients(alpha, b_hat, k)
    det_num = float(np.linalg.det(augmented_matrix_np(alpha, b_hat)))
    DET = coeff.det(alpha[k])
    out.append(
        exact(
            "DET = q2 alpha_k + q1",
            "Lemma 1, E004-03",
            f"DET = {DET:.6g}, sign*det(J_aug) = {coeff.sign * det_num:.6g}, q1 = {coeff.q1:.5g}, "
            f"q2 = {coeff.q2:.5g}",
            "DET > 0 and equal",
            DET > 0 and abs(DET - coeff.sign * det_num) < 1e-9 * max(1, abs(DET)),
            detail="exact: closed-form DET against the LU determinant of J_aug (relative tolerance 1e-9)",
        )
    )
    sg = small_gain_margin(error_dynamics_matrix(c.lambda0, c.lambda1))
    a_f = float(np.asarray(law.alpha_flfr)) if flfr else float(alpha[k])
    if n == 4 and k == 1:
        for label, a_k in (("LLFR", float(alpha[k])), ("FLFR", a_f)):
            d = coeff.d(c.b_eps, a_k)
            _, Delta, A_clp = reduced_model(c.lambda0, c.lambda1, (d[0], d[1]))
            dn = float(np.linalg.norm(Delta, 2))
            eig = np.linalg.eigvals(A_clp)
            certified = sg.norm is None or sg.norm.certified
            # ||Delta||_2 from the SVD: relative error <= 10 n eps, added before the comparison
            dn_up = dn * (1 + 10 * Delta.shape[0] * np.finfo(float).eps)
            ok = sg.holds(dn_up) if certified else None
            out.append(
                Condition(
                    f"small gain ({label}, alpha_{k + 1} = {a_k:.4g})",
                    "Theorem 1, E004-05",
                    f"||Delta||_2 = {dn:.4g} (worst eps = B_eps), gamma_1 = {sg.gamma1:.5g}",
                    f"||Delta|| < B_Delta = {sg.b_delta:.5g}",
                    ok,
                    basis="verified" if certified else "heuristic",
                    detail=(
                        "verified: gamma_1 is a certified upper bound, "
                        if certified
                        else "heuristic (gamma_1 could not be certified, nothing is proved): "
                    )
                    + f"{sg.certificate}; ||Delta||_2 with its SVD rounding bound; "
                    f"eig((I + Delta) A) = {np.round(eig, 4).tolist()}",
                )
            )
        if sup is not None and (flfr or c.alpha_flfr is not None):
            des = flfr_design(c, n, sup.e_s)
            feasible = des.verdict != "infeasible"
            out.append(
                Condition(
                    "e_s above the disturbance floor",
                    "Azizi2009 Sec. IV, T_i (E004-07)",
                    f"e_s = {sup.e_s:.4g} m, T = {des.floor:.3g} m",
                    "e_s > T_i",
                    feasible,
                    basis="verified",
                    detail="verified: T_i is a certified upper bound of sup_omega |G_i4 - G_i2| "
                    "B_ext (bounded-real certificate), so e_s > T_i holds for the true floor; "
                    "a failure is decided with the same upper bound (relative gap <= 1e-6); "
                    + des.message,
                )
            )
            if feasible:
                bound = c.b_eps * des.H / coeff.det(a_f)
                pi = c.violation_probability
                limit = sup.e_s * (1 + 1e-9) / (max(1e-12, 1 - pi) if pi > 0 else 1)
                out.append(
                    Condition(
                        "error bound (8) at the FLFR weight",
                        "Theorem 2, eq. (8), (11)",
                        f"B_eps H / DET = {bound:.4g} m (H = {des.H:.4g}, alpha_{k + 1} = {a_f:.4g}, "
                        f"pi = {pi})",
                        f"<= e_s = {sup.e_s} m (pi = 0)",
                        None if bound <= limit else False,
                        basis="sampled",
                        detail="sampled: H is the largest |X_i| of the simulated response over 300 s (RK4), not a "
                        "bound on the supremum over all t, so a pass is unproven and an excess is real"
                        + (
                            "; for pi > 0 the bound is met with probability >= 1 - pi (uniform eps)"
                            if pi > 0
                            else ""
                        ),
                    )
                )
    return out
