"""Evaluation ``chain-errors``: the true formation errors on a chain of spacecraft pairs (records and
metrics), optionally with the metric set of Azizi & Khorasani 2009; and a threshold flag (a metric
gate, e.g. the ``hierarchical`` supervisor's ``flfr_settled``).

The ``azizi2009-llfr`` law adds the true chain errors itself where the plant records positions; a
scenario that lists ``[[evaluations]] type = "chain-errors"`` replaces them (e.g. to declare the
paper's metric set, ``metrics = "azizi2009"``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal, TypedDict

from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.config.base import StrictModel
from formation_ftc.core.polygon_formation import chain_difference
from formation_ftc.sim.components import Evaluation, Signal, component
from formation_ftc.sim.contract import as_float

if TYPE_CHECKING:
    from formation_ftc.sim.metrics import Metric

__all__ = ["ChainTrackingError", "ChainErrorsSection", "EFFORT_TIME"]

#: time of the ``effort_x_100s_sc*`` metrics of the Azizi2009 set (Fig. 2 compares the efforts there) [s]
EFFORT_TIME = 100.0


@component
class ChainTrackingError(Evaluation):
    """True relative tracking errors on the chain pairs (1, 2), ..., (N-1, N) [m]::

        tracking_error_ij = (x_j - x_i) - (x_j^d - x_i^d)

    from the plant's ``position`` and the controller's ``desired_position`` signals (N, axes)."""

    def signals(self):
        e_ij = "true relative tracking error e_ij = (x_j - x_i) - (x_j^d - x_i^d)"
        return (Signal("tracking_error", ("pair", "axis"), "m", e_ij),)

    def outputs(self, signals):
        return {
            "tracking_error": chain_difference(signals["position"])
            - chain_difference(signals["desired_position"])
        }


class ChainErrorsSection(StrictModel):
    """True chain errors ``tracking_error`` e_ij = (x_j - x_i) - (x_j^d - x_i^d) on the pairs (1, 2),
    ..., (N-1, N), from the plant's positions and the law's desired polygon (records and metrics)."""

    metrics: Literal["none", "azizi2009"] = builder_input(
        "none",
        description="'azizi2009': also compute the paper's metric set -- max_err (largest |e_ij|), "
        "max_err_x, effort_x_sc* (int u_x^2 dt) and effort_x_100s_sc* (at 100 s, when the horizon "
        "reaches it) where the plant records its effort, and max_err_after_flfr, t_flfr, n_events "
        "with the hierarchical supervisor.",
    )


class _MetricOptions(TypedDict, total=False):
    """Keyword arguments of :class:`Metric` shared by several metrics of one set."""

    norm: bool
    norm_ord: str
    spacecraft: str
    units: str
    component: int


def _azizi2009_metrics(ctx: BuildContext) -> list[Metric]:
    """Azizi2009's metric set (see :class:`ChainErrorsSection`); the supervisor's metrics where the
    loop records the HL supervisor's ``flfr_settled`` flag."""
    from formation_ftc.components.supervisors.hierarchical import FLFR
    from formation_ftc.sim.metrics import Metric

    worst: _MetricOptions = {"norm": True, "norm_ord": "inf", "spacecraft": "max", "units": "m"}
    along_x: _MetricOptions = {"norm": True, "component": 0, "spacecraft": "max", "units": "m"}
    out = [
        Metric("max_err", "tracking_error", reduce="max", **worst),
        Metric("max_err_x", "tracking_error", reduce="max", **along_x),
    ]
    if any(sig.name == "flfr_settled" for ev in ctx.evaluations for sig in ev.signals()):
        out += [
            Metric(
                "max_err_after_flfr", "tracking_error", reduce="max", gate="flfr_settled", **worst
            ),
            Metric("t_flfr", "mode", reduce="first", threshold=as_float(FLFR), units="s"),
            Metric("n_events", "mode_changes", reduce="final"),
        ]
    if any(sig.name == "effort" for sig in ctx.plant.signals()):
        effort: _MetricOptions = {"component": 0, "spacecraft": "each", "units": "m2 s-3"}
        out.append(Metric("effort_x", "effort", reduce="final", **effort))
        if ctx.horizon >= EFFORT_TIME - 1e-9:
            out.append(
                Metric(
                    "effort_x_100s", "effort", reduce="at", start=as_float(EFFORT_TIME), **effort
                )
            )
    return out


def _build(sec: ChainErrorsSection, ctx: BuildContext) -> ChainTrackingError:
    """The evaluation of a validated ``[[evaluations]] type = "chain-errors"`` item; it replaces the
    chain errors the law added."""
    ctx.evaluations[:] = [ev for ev in ctx.evaluations if not isinstance(ev, ChainTrackingError)]
    if sec.metrics == "azizi2009":
        ctx.metrics.extend(_azizi2009_metrics(ctx))
    return ChainTrackingError()


register(
    "evaluation",
    "chain-errors",
    ChainErrorsSection,
    _build,
    "true chain errors e_ij (tracking_error); metrics = 'azizi2009': the paper's metric set",
)
