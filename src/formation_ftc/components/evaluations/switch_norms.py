"""Evaluation ``switch-norms``: metrics of Yang2013's switched formation -- sup |X| over both limits
of every switch, |X| at both limits of every switch (per spacecraft before it), final |X|, max |u_i|
on stated windows, and the supervisor's decisions. Metrics only: the signals are the
``switched-formation`` plant's (``error-state``) and the switches the ``switching`` supervisor's plan
(``switching-plan``)."""

from __future__ import annotations

from functools import partial

import numpy as np

from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.components.supervisors.switching import (
    SwitchingSupervisorSection,
    switched_structure,
)
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import Evaluation, component
from formation_ftc.sim.contract import as_float

__all__ = ["SwitchNorms", "SwitchNormsSection"]


@component
class SwitchNorms(Evaluation):
    """No signals of its own: the metrics of ``switch-norms`` read the plant's and the supervisor's."""

    def needs(self) -> dict[str, str]:
        return {
            "error-state": "score the norms of the error state and of the inputs",
            "switching-plan": "score the norms at both limits of every switch",
        }


class SwitchNormsSection(StrictModel):
    """Metrics of the switched loop (module docstring), and maxima of |u_i| on stated windows."""

    input_windows: list[tuple[float, float]] = builder_input(
        default_factory=list,
        description="Windows [a, b) [s] of further every-step maxima of |u_i| per spacecraft "
        "(metrics max_input_norm_<a>_<b>_sc<i>).",
    )


def _build(sec: SwitchNormsSection, ctx: BuildContext) -> SwitchNorms:
    """The metrics of a validated ``[[evaluations]] type = "switch-norms"`` entry (to ``ctx.metrics``),
    the switches' from the ``[supervisor]``'s plan (without one, none: the loop is refused for the
    missing ``switching-plan``)."""
    from formation_ftc.sim.metrics import Metric

    plan = ctx.section("supervisor")
    switch_steps = (
        switched_structure(plan, ctx.count, ctx.dt).switch_steps
        if isinstance(plan, SwitchingSupervisorSection)
        else np.zeros(1, dtype=np.int64)
    )
    n_steps = ctx.scenario.simulation.n_steps
    each = partial(Metric, spacecraft="each", units="1")  # one metric per spacecraft
    ctx.metrics.extend(
        [
            Metric("max_state_norm", "state_norm_peak", reduce="max", units="1"),
            Metric("final_state_norm", "state_norm", reduce="final", units="1"),
        ]
    )
    windows = [("max_input_norm", 0.0, n_steps * ctx.dt)]  # [0, horizon), then the stated ones
    windows += [(f"max_input_norm_{a:g}_{b:g}", a, b) for a, b in sec.input_windows]
    for name, a, b in windows:  # every step of [a, b): the window ends half a step before b
        ctx.metrics.append(
            each(name, "input_norm", "max", start=as_float(a), end=as_float(b - 0.5 * ctx.dt))
        )
    for j in range(1, len(switch_steps)):
        if switch_steps[j] > n_steps:  # never reached (short runs)
            continue
        t = as_float(switch_steps[j] * ctx.dt)
        ctx.metrics.extend(
            [
                Metric(f"pre_switch_norm_{j + 1}", "state_norm_left", "at", units="1", start=t),
                Metric(f"post_switch_norm_{j + 1}", "state_norm", "at", units="1", start=t),
                each(f"pre_switch_sc_norm_{j + 1}", "spacecraft_norm_left", "at", start=t),
            ]
        )
    # decision codes (0 none, 1 tolerate by switching, 2 reconfigure); times, modes and (29) margins
    # are recorded signals (the last record holds every decision)
    ctx.metrics.append(
        Metric("supervisor_decision", "supervisor_decision", reduce="final", spacecraft="each")
    )
    return SwitchNorms()


register(
    "evaluation",
    "switch-norms",
    SwitchNormsSection,
    _build,
    "|X| at both limits of every switch, sup |X|, max |u_i|, decisions (metrics only)",
)
