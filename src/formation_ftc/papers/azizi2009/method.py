"""Registration of the ``azizi2009`` method: schema, build, condition checks and scenario figures.

Conditions (``formation-ftc check``), all from Azizi & Khorasani 2009 / SPEC.md P4:

* allocation inputs valid (alpha_i > 0, b_hat_i > 0; eq. (3));
* Lemma 1 / E004-03: DET = q2 alpha_2 + q1 > 0 and equal to -det(J_aug);
* Theorem 1 (small gain): ||Delta||_2 < B_Delta = 1 / gamma_1 for the LLFR and the FLFR weights;
* B_eps covers the actual estimation error |b_hat - b| (informational: it uses the true b);
* Theorem 2 / eq. (11): the FLFR design is feasible (e_s above the disturbance floor T_i) and the
  bound (8) at the FLFR weight is <= e_s.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from formation_ftc.design.allocation import augmented_matrix, perturbation_coefficients
from formation_ftc.design.flfr import error_dynamics_matrix, reduced_model
from formation_ftc.design.small_gain import small_gain_margin
from formation_ftc.papers.azizi2009.model import _alpha_flfr, _b_hat_estimated, _b_true, build, flfr_design
from formation_ftc.papers.azizi2009.schema import Azizi2009Scenario
from formation_ftc.registry import Condition, Method, register_method

__all__ = ["check", "plot", "METHOD"]


def check(sc: Azizi2009Scenario) -> list[Condition]:
    """Evaluate the paper's design conditions for a scenario (see module docstring)."""
    out: list[Condition] = []
    n = sc.formation.n_satellites
    alpha = np.asarray(sc.allocation.alpha, float)
    out.append(Condition("allocation weights", "Azizi2009 eq. (3)", f"alpha = {alpha.tolist()}",
                         "alpha_i > 0", bool(np.all(alpha > 0))))
    if not sc.fault.enabled:
        out.append(Condition("fault-free allocation", "Azizi2009 eq. (4)", "b_hat = b",
                             "exact cancellation: e'' = -l1 e' - l0 e", True, required=False))
        return out
    k = sc.fault.satellite - 1
    ax = "xyz".index(sc.fault.axis)
    b_hat = _b_hat_estimated(sc)[:, ax]
    b_true = _b_true(sc)[:, ax]
    eps = float(b_hat[k] - b_true[k])
    out.append(Condition("estimation error within B_eps", "Azizi2009 Sec. IV, |eps| < B_eps",
                         f"|eps| = {abs(eps):.4g}, B_eps = {sc.fault.b_eps:.4g}", "|b_hat - b| <= B_eps",
                         abs(eps) <= sc.fault.b_eps + 1e-12, required=False,
                         detail="uses the true gain (truth side); the design only knows B_eps"))
    if not 0 < k < n - 1:
        out.append(Condition("interior faulty satellite", "Azizi2009 eq. (6)-(7)", f"satellite {k + 1}",
                             f"2..{n - 1} for the reduced model (7)", None, required=False))
        return out
    coeff = perturbation_coefficients(alpha, b_hat, k)
    det_num = float(np.linalg.det(np.asarray(augmented_matrix(alpha, b_hat))))
    DET = coeff.det(alpha[k])
    out.append(Condition("DET = q2 alpha_k + q1", "Lemma 1, E004-03",
                         f"DET = {DET:.6g}, sign*det(J_aug) = {coeff.sign * det_num:.6g}, q1 = {coeff.q1:.5g}, "
                         f"q2 = {coeff.q2:.5g}", "DET > 0 and equal", DET > 0 and abs(DET - coeff.sign * det_num) < 1e-9 * max(1, abs(DET))))
    lam0, lam1 = sc.controller.lambda0, sc.controller.lambda1
    sg = small_gain_margin(error_dynamics_matrix(lam0, lam1))
    try:
        a_f: float | None = _alpha_flfr(sc) if sc.supervisor.flfr else float(alpha[k])
    except ValueError:  # infeasible design: reported by the floor condition below
        a_f = None
    if n == 4 and k == 1:
        weights = [("LLFR", float(alpha[k]))] + ([("FLFR", a_f)] if a_f is not None else [])
        for label, a_k in weights:
            d = coeff.d(sc.fault.b_eps, a_k)
            _, Delta, A_clp = reduced_model(lam0, lam1, (d[0], d[1]))
            dn = float(np.linalg.norm(Delta, 2))
            eig = np.linalg.eigvals(A_clp)
            out.append(Condition(
                f"small gain ({label}, alpha_{k + 1} = {a_k:.4g})", "Theorem 1, E004-05",
                f"||Delta||_2 = {dn:.4g} (worst eps = B_eps), gamma_1 = {sg.gamma1:.5g}",
                f"||Delta|| < B_Delta = {sg.b_delta:.5g}", sg.holds(dn),
                detail=f"eig((I + Delta) A) = {np.round(eig, 4).tolist()}"))
        if sc.supervisor.flfr or sc.supervisor.alpha_flfr is not None:
            des = flfr_design(sc)
            feasible = des.verdict != "infeasible"
            out.append(Condition("e_s above the disturbance floor", "Azizi2009 Sec. IV, T_i (E004-07)",
                                 f"e_s = {sc.supervisor.e_s:.4g} m, T = {des.floor:.3g} m",
                                 "e_s > T_i", feasible, detail=des.message))
            if feasible and a_f is not None:
                bound = sc.fault.b_eps * des.H / coeff.det(a_f)
                out.append(Condition(
                    "error bound (8) at the FLFR weight", "Theorem 2, eq. (8), (11)",
                    f"B_eps H / DET = {bound:.4g} m (H = {des.H:.4g}, alpha_{k + 1} = {a_f:.4g}, "
                    f"pi = {sc.supervisor.violation_probability})", f"<= e_s = {sc.supervisor.e_s} m (pi = 0)",
                    bound <= sc.supervisor.e_s * (1 + 1e-9) / max(1e-12, 1 - sc.supervisor.violation_probability)
                    if sc.supervisor.violation_probability > 0 else bound <= sc.supervisor.e_s * (1 + 1e-9),
                    detail="for pi > 0 the bound is met with probability >= 1 - pi (uniform eps)"))
    return out


def plot(ds, sc: Azizi2009Scenario, out_dir: Path) -> list[Path]:
    """Tracking errors and cumulative efforts of one run (x axis), with the mode and e_s."""
    from formation_ftc.papers.azizi2009.figures import plot_run

    return plot_run(ds, sc, Path(out_dir))


METHOD = register_method(Method(
    name="azizi2009", schema=Azizi2009Scenario, build=build,
    description="Azizi & Khorasani 2009: deep-space double integrators, LLFR allocation, HL supervisor, FLFR",
    check=check, plot=plot))
