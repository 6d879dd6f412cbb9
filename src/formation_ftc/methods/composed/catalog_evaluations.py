"""Catalog: evaluation signals (``[[evaluations]]``) -- truth-side scores for records and metrics."""

from __future__ import annotations

import numpy as np
from pydantic import Field

from formation_ftc.components.evaluations.formation_scores import FormationScores
from formation_ftc.config.base import StrictModel
from formation_ftc.methods.composed import BuildContext, per_spacecraft, register_component_type
from formation_ftc.sim.components import CompositionError, as_float

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
