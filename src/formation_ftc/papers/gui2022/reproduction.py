"""Reproduction ``gui2022``: Figs. 3-10 of Gui et al. 2022, summary metrics, published-vs-ours rows.

Declared in ``study.toml`` (runs of 3,000 s at dt = tau = 1 ms, i.e. 3 million steps, E002-10: the new
ILO with the printed, LMI-designed and rescaled LMI gains as one vmapped batch, the ILO of [25], the ILO
from an offset estimate (Figs. 4-5), LOF2TC and COF2TC); :func:`prepare` designs the LMI gains before
the runs (E002-06), :func:`quantities` computes the numbers. The reproduction uses the printed L1, L2, K.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from formation_ftc.papers._study import Run, study
from formation_ftc.papers.gui2022 import published as pub

__all__ = ["REPRODUCTION", "prepare", "quantities"]

#: run name -> short name in the quantities (its deputy's dataset; its metrics as m_<short>)
_SHORT = {"gui2022-ilo": "ilo", "gui2022-ilo-lmi": "lmi", "gui2022-ilo-lmi-scaled": "lmis"}
_SHORT |= {"gui2022-ilo-baseline": "base", "gui2022-ilo-offset": "off"}
_SHORT |= {"gui2022-lof2tc": "lof", "gui2022-cof2tc": "cof"}


def prepare(constants: dict) -> dict:
    """The LMI design of the new ILO (normalised P >= I) and its rescaling to the printed L2 (E002-06)."""
    from formation_ftc.components.estimators.iterative_learning_observer import ilo_lmi_design

    des = ilo_lmi_design(pub.N_MEAN_MOTION, 1e-8, -5.0, 2.0)
    scale = float(pub.L2_PRINTED[0, 3] / des.L2[0, 3])
    return {"lmi_design": des, "lmi_scale": scale, "estimate_offset": list(pub.ESTIMATE_OFFSET)}


def quantities(runs: dict[str, Run], constants: dict) -> dict:
    """The numbers ``study.toml`` reads (every one accumulated in-run at every step)."""
    from formation_ftc.components.controllers._output_feedback import care_solution
    from formation_ftc.components.evaluations.gui2022_scores import (
        ESTIMATE_ERROR_AT,
        LOWPASS_WINDOW,
    )
    from formation_ftc.core.dynamics.cw import cw_matrices
    from formation_ftc.methods.composed import make_loop
    from formation_ftc.papers.gui2022 import figures as F
    from formation_ftc.papers.gui2022.conditions import controller_conditions, observer_conditions

    m = {_SHORT[name]: r.metrics for name, r in runs.items()}
    q: dict[str, Any] = {_SHORT[name]: F.deputy(r.dataset) for name, r in runs.items()}
    q["baseline"], q["offset"] = q["base"], q["off"]
    q |= {f"m_{k}": v for k, v in m.items()}
    q |= {f"{k}:{name}": value for k, v in m.items() for name, value in v.items()}
    des, n = constants["lmi_design"], pub.N_MEAN_MOTION
    e_at = {tt: m["off"][f"estimate_pos_err_at_{tt:g}s"] for tt in ESTIMATE_ERROR_AT}

    def lowpass_rms(name: str) -> float:
        """Fig. 10's low-pass RMS of a 3-vector: the block means of each axis combine exactly."""
        return float(np.sqrt(sum(m["lof"][f"{name}_lowpass_rms_{a}"] ** 2 for a in "xyz")))

    v_h_rms, h_rms = lowpass_rms("compensation_error"), lowpass_rms("synthesized_disturbance")
    A, B = cw_matrices(n)
    care = care_solution(n, pub.CARE_Q_SCALE)
    ref = constants["offset_error_reference"]
    q["dP"] = float(np.max(np.abs(care.P - pub.P1_PRINTED)))
    q["care_residual"] = float(care.residual)
    q |= {"k_equal": bool(np.allclose(np.round(B.T @ care.P, 4), pub.K_PRINTED, atol=1e-12))}
    q |= {"L1_00": float(des.L1[0, 0]), "L1_03": des.L1[0, 3], "L1_34": des.L1[3, 4]}
    q |= {"L2_03": float(des.L2[0, 3]), "lmi_solver": des.solver, "lowpass_window": LOWPASS_WINDOW}
    q |= {f"lmi_{k}": float(des.residuals[k]) for k in ("max_eig_8", "max_eig_27", "max_eig_disk")}
    q["lmi_poles_max_distance"] = float(des.residuals["max_pole_distance"])
    q |= {"e_at_0": e_at[0.0], "e_at_1": e_at[1.0], "e_at_2": e_at[2.0]}
    q |= {"reference_1": ref["1"], "reference_2": ref["2"], "half_h_rms": 0.5 * h_rms}
    q |= {"v_h_rms": v_h_rms, "h_rms": h_rms, "ilo_chatter": _chatter(m["ilo"])}
    q["base_chatter"] = _chatter(m["base"])
    q["horizon_s"] = float(runs["gui2022-lof2tc"].scenario.simulation.horizon)
    q["run_wall_s"] = {name: round(r.run_s, 3) for name, r in runs.items()}
    q["compile_wall_s"] = {name: round(r.compile_s, 3) for name, r in runs.items()}
    scn = runs["gui2022-lof2tc"].scenario
    loop = make_loop(scn)
    q["checks"] = observer_conditions(scn, loop) + controller_conditions(scn, loop)
    q["scenarios"] = ["gui2022-ilo", "gui2022-ilo-baseline", "gui2022-lof2tc", "gui2022-cof2tc"]
    return q


def _chatter(m: dict) -> float:
    """Largest over the axes of the RMS of F_hat about its boxcar mean over [fault_rms_delay, x onset)
    (100 s to 1500 s): the amplitude of the period-2 chatter."""
    return float(max(m[f"fault_estimate_chatter_rms_{ax}"] for ax in "xyz"))


REPRODUCTION = study("gui2022", quantities, prepare)
