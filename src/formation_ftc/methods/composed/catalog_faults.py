"""Catalog: the fault-battery actuator (per-axis saturation + one thruster-level fault of a named kind)
and communication faults on a graph network (links lost, delays scaled after an onset).

``[actuator] type = "fault-battery"``::

    kind = "loss_of_effectiveness"   # none, loss_of_effectiveness, bias, stuck, outage, intermittent, degrading
    spacecraft = 2                   # faulty spacecraft, 1-based
    axis = 0                         # faulty axis 0, 1, 2
    onset = 1000.0                   # [s]
    effectiveness = 0.5              # loss_of_effectiveness [-]
    bias = 0.0                       # bias [N, or N m on a torque plant]
    period = 60.0                    # intermittent [s]
    duty = 0.5                       # intermittent on-fraction [-]
    rate = 0.0                       # degrading [1/s]
    min_effectiveness = 0.0          # degrading floor [-]
    saturation = 1.0                 # per-axis limit [N or N m]: one number or one per spacecraft; omit: none
    euler_allocation = false         # the law commands a 3-2-1 Euler-angle generalised torque

``[network] type = "graph-link-loss"``: the ``graph`` fields (``adjacency``), optionally ``delays`` and
``max_delay`` of ``delayed-graph``, plus ``lost_links`` (pairs [i, j], 1-based: receiver i stops hearing
sender j), ``onset`` [s], ``delay_scale`` [-] and ``max_delay_scale`` [-] (delayed graphs only).

Every number becomes an array leaf, so cases that differ only in these fields (kind included) share one
compiled program.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from pydantic import Field, ValidationInfo, field_validator, model_validator

from formation_ftc.components.networks.delayed_graph import delayed_graph_network
from formation_ftc.components.networks.graph import GraphSection
from formation_ftc.config.base import ExprText, StrictModel
from formation_ftc.core.constants import FAULT_KINDS
from formation_ftc.methods.composed import BuildContext, per_spacecraft, register_component_type
from formation_ftc.sim.contract import as_float

if TYPE_CHECKING:
    from formation_ftc.components.actuators.fault_battery import FaultBatteryActuator

__all__ = ["FaultBatterySection", "GraphLinkLossSection", "FAULT_BATTERY", "GRAPH_LINK_LOSS"]

FAULT_BATTERY = "fault-battery"
GRAPH_LINK_LOSS = "graph-link-loss"


# -------------------------------------------------------------------------------------- actuators
class FaultBatterySection(StrictModel):
    """Per-axis saturation, then one fault of kind ``kind`` on channel (spacecraft, axis) from ``onset``."""

    kind: str = Field("none", description=f"Fault kind: one of {', '.join(FAULT_KINDS)}.")
    spacecraft: int = Field(1, ge=1, description="Faulty spacecraft (1-based) [-].")
    axis: int = Field(0, ge=0, le=2, description="Faulty axis 0, 1 or 2 [-].")
    onset: float = Field(
        0.0, ge=0.0, description="Fault onset (acts from the first step at or after it) [s]."
    )
    effectiveness: float = Field(
        1.0, ge=0.0, description="Gain of a loss_of_effectiveness fault [-]."
    )
    bias: float = Field(
        0.0, description="Additive output of a bias fault [N, or N m on a torque plant]."
    )
    period: float = Field(60.0, gt=0.0, description="Period of an intermittent fault [s].")
    duty: float = Field(
        0.5, ge=0.0, le=1.0, description="On-fraction of each intermittent period [-]."
    )
    rate: float = Field(
        0.0, ge=0.0, description="Effectiveness loss rate of a degrading fault [1/s]."
    )
    min_effectiveness: float = Field(
        0.0, ge=0.0, le=1.0, description="Floor of a degrading fault's effectiveness [-]."
    )
    saturation: float | list[float] | None = Field(
        None,
        description="Per-axis output limit [N or N m], one number or one per spacecraft (omit: unsaturated).",
    )
    euler_allocation: bool = Field(
        False,
        description="Map a generalised 3-2-1 Euler-angle torque to the body "
        "torque first (quaternion plants).",
    )

    @field_validator("kind")
    @classmethod
    def _kind(cls, v: str) -> str:
        if v not in FAULT_KINDS:
            raise ValueError(
                f"kind = {v!r} is not a fault kind (allowed: {', '.join(FAULT_KINDS)})"
            )
        return v

    @field_validator("saturation")
    @classmethod
    def _limits(cls, v):
        lim = [] if v is None else np.atleast_1d(np.asarray(v, float)).tolist()
        if any(not (x > 0 and math.isfinite(x)) for x in lim):
            raise ValueError(
                f"saturation = {v}: limits must be finite and > 0 [N or N m] (omit it for none)"
            )
        return v


def _fault_battery(sec: FaultBatterySection, ctx: BuildContext) -> FaultBatteryActuator:
    from formation_ftc.components.actuators.fault_battery import (
        FaultBatteryActuator,
        fault_kind_code,
    )

    n = ctx.count
    if sec.spacecraft > n:
        raise ValueError(
            f"actuator.spacecraft = {sec.spacecraft}: must be in 1..{n} (plant "
            f"{ctx.scenario.type_of('plant')} has {n} spacecraft)"
        )
    limit = np.inf if sec.saturation is None else sec.saturation
    sat = per_spacecraft(limit, n, "actuator.saturation")
    quantity = getattr(ctx.plant, "quantity", "force")
    return FaultBatteryActuator(
        count=n,
        saturation=as_float(sat),
        fault_kind=as_float(fault_kind_code(sec.kind)),
        spacecraft=as_float(sec.spacecraft),
        axis=as_float(sec.axis),
        onset=as_float(sec.onset),
        effectiveness=as_float(sec.effectiveness),
        bias=as_float(sec.bias),
        period=as_float(sec.period),
        duty=as_float(sec.duty),
        rate=as_float(sec.rate),
        min_effectiveness=as_float(sec.min_effectiveness),
        euler_allocation=sec.euler_allocation,
        units="N m" if quantity == "torque" else "N",
    )


register_component_type(
    "actuator",
    FAULT_BATTERY,
    FaultBatterySection,
    _fault_battery,
    "per-axis saturation + one fault (loss of effectiveness, bias, stuck, outage, "
    "intermittent, degrading) on one channel from an onset; kind and numbers are leaves",
)


# ---------------------------------------------------------------------------------------- networks
class GraphLinkLossSection(GraphSection):
    """A graph (optionally delayed) whose listed links stop delivering, and delays scale, from ``onset``."""

    delays: list[list[ExprText]] | None = Field(
        None,
        description="T_ij(t) per link, expressions in t, i, j [s] (N x N), >= 0; omit: no delays.",
    )
    max_delay: float | None = Field(
        None, gt=0, description="Largest unscaled delay on any used link [s] (with delays)."
    )
    lost_links: list[tuple[int, int]] = Field(
        default_factory=list,
        description="Links [i, j] (1-based) that stop delivering: receiver i no longer hears j.",
    )
    onset: float = Field(0.0, ge=0.0, description="Onset of the communication fault [s].")
    delay_scale: float = Field(
        1.0,
        gt=0.0,
        description="Every delay is multiplied by this after the onset [-] (delayed graphs only).",
    )
    max_delay_scale: float | None = Field(
        None,
        gt=0.0,
        description="Largest delay_scale the history buffer must serve [-] (default: delay_scale); "
        "give the batch's largest so cases of several scales share one program.",
    )

    @field_validator("lost_links")
    @classmethod
    def _links(cls, v, info: ValidationInfo):
        adjacency = info.data.get("adjacency") or []
        n = len(adjacency)
        for k, (i, j) in enumerate(v):
            if not (1 <= i <= n and 1 <= j <= n):
                raise ValueError(
                    f"lost_links[{k}] = [{i}, {j}]: spacecraft numbers must be in 1..{n}"
                )
            if not (len(adjacency[i - 1]) >= j and adjacency[i - 1][j - 1] > 0):
                raise ValueError(
                    f"lost_links[{k}] = [{i}, {j}]: adjacency[{i - 1}][{j - 1}] = 0, "
                    f"spacecraft {i} does not receive from {j}"
                )
        return v

    @field_validator("delay_scale")
    @classmethod
    def _scale(cls, v, info: ValidationInfo):
        if info.data.get("delays") is None and v != 1.0:
            raise ValueError(
                f"delay_scale = {v}: the graph has no delays to scale (give delays and max_delay, "
                "or delay_scale = 1)"
            )
        return v

    @model_validator(mode="after")
    def _delays(self):
        if (self.delays is None) != (self.max_delay is None):
            raise ValueError("delays and max_delay: give both (delayed graph) or neither")
        if self.max_delay_scale is not None and self.max_delay_scale < self.delay_scale:
            raise ValueError(
                f"max_delay_scale = {self.max_delay_scale} must be >= delay_scale = {self.delay_scale}"
            )
        return self

    def lost_mask(self) -> np.ndarray:
        """(N, N) mask, 1 where link (i <- j) is lost [-]."""
        n = len(self.adjacency)
        mask = np.zeros((n, n))
        for i, j in self.lost_links:
            mask[i - 1, j - 1] = 1.0
        return mask


def _graph_link_loss(sec: GraphLinkLossSection, ctx: BuildContext):
    from formation_ftc.components.networks.link_faults import (
        DelayedGraphLinkLossNetwork,
        GraphLinkLossNetwork,
    )
    from formation_ftc.core.history import required_capacity

    lost, onset = as_float(sec.lost_mask()), as_float(sec.onset)
    if sec.delays is None:
        return GraphLinkLossNetwork(adjacency=as_float(sec.adjacency), lost=lost, onset=onset)
    base = delayed_graph_network(sec, ctx)  # type: ignore[arg-type]  # same adjacency / delays / max_delay fields
    # the history holds the scaled delays too
    scale = sec.delay_scale if sec.max_delay_scale is None else sec.max_delay_scale
    capacity = required_capacity(float(sec.max_delay or 0.0) * max(1.0, scale), ctx.dt) + 1
    return DelayedGraphLinkLossNetwork(
        adjacency=base.adjacency,
        delays=base.delays,
        edges=base.edges,
        capacity=capacity,
        dt=base.dt,
        lost=lost,
        onset=onset,
        delay_scale=as_float(sec.delay_scale),
    )


register_component_type(
    "network",
    GRAPH_LINK_LOSS,
    GraphLinkLossSection,
    _graph_link_loss,
    "weighted directed graph (optionally delayed) whose listed links stop delivering, and "
    "whose delays scale, after an onset",
)
