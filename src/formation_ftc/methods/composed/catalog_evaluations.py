"""Catalog: evaluation signals (``[[evaluations]]``) -- truth-side scores for records and metrics.

* ``formation-scores``: slot and shape errors, thrust and delivered acceleration against common slots;
* ``li2020-formation-errors``: Li2020's mu1, mu2 (literal, E000-08) and mu2_vc
  (:class:`~formation_ftc.components.evaluations.formation_errors.FormationErrors`) and the li2020
  report's metric set (:func:`li2020_metrics`), every one accumulated at every step inside the run.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from pydantic import Field

from formation_ftc.config.base import StrictModel
from formation_ftc.methods.composed import BuildContext, per_spacecraft, register_component_type
from formation_ftc.sim.contract import CompositionError, as_float

if TYPE_CHECKING:
    from formation_ftc.sim.metrics import Metric

Vec3 = tuple[float, float, float]


class FormationScoresSection(StrictModel):
    """Slot error, shape error, thrust and delivered acceleration against common desired slots."""

    desired: list[Vec3] = Field(
        description="Desired slot of each spacecraft in the plant's formation frame [m]."
    )
    mass: float | list[float] | None = Field(
        None, description="True masses [kg] (default: the plant's `mass`)."
    )


def _formation_scores(sec: FormationScoresSection, ctx: BuildContext):
    from formation_ftc.components.evaluations.formation_scores import FormationScores

    n = ctx.count
    if ctx.plant is None or not any(s.name == "position" for s in ctx.plant.signals()):
        raise CompositionError(
            f"evaluation formation-scores reads the plant's position, but plant "
            f"{ctx.scenario.type_of('plant')} records none"
        )
    if ctx.plant.quantity != "force":
        raise CompositionError(
            f"evaluation formation-scores scores forces, but plant "
            f"{ctx.scenario.type_of('plant')} is driven by a {ctx.plant.quantity}"
        )
    desired = np.asarray(sec.desired, dtype=float)
    if desired.shape != (n, 3):
        raise ValueError(f"evaluations.desired: {len(sec.desired)} slots for {n} spacecraft")
    mass = sec.mass if sec.mass is not None else getattr(ctx.section("plant"), "mass", None)
    if mass is None:
        raise ValueError("evaluations.mass: the plant has no masses; give the true masses [kg]")
    m = per_spacecraft(mass, n, "evaluations.mass")
    if np.any(~(m > 0)):
        raise ValueError(f"evaluations.mass = {list(m)}: every mass must be > 0 [kg]")
    return FormationScores(desired=as_float(desired), mass=as_float(m))


register_component_type(
    "evaluation",
    "formation-scores",
    FormationScoresSection,
    _formation_scores,
    "slot error, shape error, applied thrust and delivered acceleration against common slots",
)


#: times [s] of the mu1_at_<t>s metrics (those within the horizon)
MU1_AT = (10.0, 20.0, 30.0, 100.0, 300.0, 1000.0, 3000.0)
#: window [s] of ``mu1_max_50_300s`` (the E000-04 comparison of the literal and corrected d_hat sign;
#: declared when the horizon reaches its end)
E000_04_WINDOW = (50.0, 300.0)
#: adaptive parameters (recorded signals) of the laws compared in Li2020, with their units
ADAPTIVE = {
    "li2020-adaptive": {"m_hat": "kg", "beta_hat": "1", "d_hat": "N"},
    "sir-ftc": {"b_hat": "N"},
}


class Li2020FormationErrorsSection(StrictModel):
    """No fields: mu1, mu2, mu2_vc and the li2020 metrics of the run's horizon."""


def li2020_metrics(horizon: float, controller: str | None) -> tuple[Metric, ...]:
    """The metrics of a Li2020 run (every step inside the run).

    Parameters
    ----------
    horizon : float
        The run's horizon T [s]: windows and samples relative to it (last 10 %, ``mu1_at_<t>s`` within
        it, the E000-04 window when T reaches its end).
    controller : str or None
        The controller type: the final values and the values at 0.9 T of its adaptive parameters
        (``ADAPTIVE``) are added for ``li2020-adaptive`` and ``sir-ftc``.

    Returns
    -------
    tuple of Metric
        Final values, maxima, 1 m settling time of mu1 [s], delta-v [m/s], peak force [N], ...
    """
    from formation_ftc.sim.metrics import Metric

    T = float(horizon)
    # values at the horizon: "last" (read once after the loop, no per-step cost)
    m = [
        Metric("mu1_final", "mu1", "last", units="m"),
        Metric("mu2_final", "mu2", "last", units="m"),
        Metric("mu2_vc_final", "mu2_vc", "last", units="m"),
        Metric("mu1_max_last_10pct", "mu1", "max", units="m", start=as_float(0.9 * T)),
        Metric("settle_time_mu1_1m", "mu1", "settle", units="s", threshold=as_float(1.0)),
        Metric("mu1_max_after_50s", "mu1", "max", units="m", start=as_float(50.0)),
        Metric("delta_v_total", "delta_v", "last", spacecraft="sum", units="m s-1"),
        Metric(
            "max_control_force",
            "command",
            "max",
            norm=True,
            norm_ord="inf",
            spacecraft="max",
            units="N",
        ),
    ]
    m += [
        Metric(f"mu1_at_{int(tq)}s", "mu1", "at", units="m", start=as_float(tq))
        for tq in MU1_AT
        if tq <= T + 1e-9
    ]
    m += [
        Metric("delta_v", "delta_v", "last", spacecraft="each", units="m s-1"),
        Metric(
            "position_error_final",
            "position_error",
            "last",
            norm=True,
            spacecraft="each",
            units="m",
        ),
        Metric(
            "velocity_error_final",
            "velocity_error",
            "last",
            norm=True,
            spacecraft="each",
            units="m s-1",
        ),
    ]
    lo, hi = E000_04_WINDOW
    if T >= hi - 1e-9:
        m.append(
            Metric("mu1_max_50_300s", "mu1", "max", units="m", start=as_float(lo), end=as_float(hi))
        )
    units = ADAPTIVE.get(str(controller), {})
    m += [Metric(f"{n}_final", n, "last", spacecraft="each", units=u) for n, u in units.items()]
    # value at the step t = 0.9 T (the adaptive parameters' drift over the last 10 % of the horizon)
    m += [
        Metric(f"{n}_at_90pct", n, "at", spacecraft="each", units=u, start=as_float(0.9 * T))
        for n, u in units.items()
    ]
    return tuple(m)


def _li2020_formation_errors(sec: Li2020FormationErrorsSection, ctx: BuildContext):
    from formation_ftc.components.evaluations.formation_errors import FormationErrors

    ctx.metrics.extend(li2020_metrics(ctx.horizon, ctx.scenario.type_of("controller")))
    return FormationErrors()


register_component_type(
    "evaluation",
    "li2020-formation-errors",
    Li2020FormationErrorsSection,
    _li2020_formation_errors,
    "Li2020 formation errors mu1, mu2 (literal), mu2_vc and the li2020 report's metrics",
)
