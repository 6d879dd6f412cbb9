"""Evaluation ``mehrabian-metrics``: Mehrabian's metric set (synchronisation and tracking errors,
effort, spreads of the Euler angles) over the fault window, the run and the assessment window.

The type declares metrics (:class:`~formation_ftc.sim.metrics.Metric`) on the signals of the
Euler-angle law (``networked-el-hinf``: the capability ``euler-angle-law``) and of the Euler-angle plant
(``euler-angle-attitude``: ``euler-angle-attitude-state``), and a :class:`MehrabianMetrics` evaluation
that records nothing and states those two needs, so that a loop without them is refused before
anything runs. :func:`metric_windows` gives a scenario's windows (the Mehrabian reproduction and
figures).
"""

from __future__ import annotations

from typing import Any, TypedDict

from pydantic import Field, model_validator

from formation_ftc.components._registry import BuildContext, register
from formation_ftc.components.plants.euler_angle_attitude import AXES
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import Evaluation, component
from formation_ftc.sim.contract import as_float

__all__ = ["MehrabianMetrics", "MehrabianMetricsSection", "metric_windows", "clipped_windows"]


@component
class MehrabianMetrics(Evaluation):
    """Records nothing: the loop's metrics are Mehrabian's (module docstring); states what they read."""

    def needs(self) -> dict[str, str]:
        return {
            "euler-angle-law": "score its tracking and synchronisation errors",
            "euler-angle-attitude-state": "score the spread of the plant's Euler angles",
        }


class MehrabianMetricsSection(StrictModel):
    """Mehrabian's metric set over three windows (fault window, whole run, assessment window), clipped
    to the horizon; a window that starts after the horizon yields no metrics."""

    fault_window: tuple[float, float] = Field(
        (40.0, 240.0), description="Window of the fault-window metrics [s]."
    )
    assessment_window: tuple[float, float] = Field(
        (45.0, 240.0),
        description="Window of the reproduction's comparisons (from the reconfiguration) [s].",
    )

    @model_validator(mode="after")
    def _order(self):
        for name in ("fault_window", "assessment_window"):
            a, b = getattr(self, name)
            if not 0 <= a < b:
                raise ValueError(f"{name} = [{a}, {b}]: need 0 <= start < end [s]")
        return self


def clipped_windows(sec: MehrabianMetricsSection, H: float) -> dict[str, tuple[float, float]]:
    """The three windows of a section, clipped to the horizon.

    Parameters
    ----------
    sec : MehrabianMetricsSection
        A validated section.
    H : float
        The horizon [s].

    Returns
    -------
    dict
        ``{"fault_window": (a, b), "run": (0, H), "assessment_window": (a, b)}`` [s].

    Examples
    --------
    >>> clipped_windows(MehrabianMetricsSection(), 100.0)["fault_window"]
    (40.0, 100.0)
    """
    raw = {
        "fault_window": sec.fault_window,
        "run": (0.0, H),
        "assessment_window": sec.assessment_window,
    }
    return {w: (min(float(a), H), min(float(b), H)) for w, (a, b) in raw.items()}


def metric_windows(scenario: Any) -> dict[str, tuple[float, float]] | None:
    """The windows [s] of a composed scenario's ``mehrabian-metrics`` evaluation (fault window, run,
    assessment window), clipped to the horizon; None without one.

    Parameters
    ----------
    scenario : ComposedScenario
        A validated composed scenario.

    Returns
    -------
    dict or None
        ``{"fault_window": (a, b), "run": (0, H), "assessment_window": (a, b)}`` [s].

    Examples
    --------
    >>> import formation_ftc as ftc
    >>> metric_windows(ftc.load_scenario("mehrabian-identification"))["assessment_window"]
    (45.0, 240.0)
    >>> metric_windows(ftc.load_scenario("cw-pd-fault")) is None
    True
    """
    sec = next((v for n, v in scenario._evaluation_sections if n == "mehrabian-metrics"), None)
    return None if sec is None else clipped_windows(sec, float(scenario.simulation.horizon))


class _Opts(TypedDict, total=False):
    """Keyword arguments of :class:`Metric` that vary between the rows of a metric table."""

    norm: bool
    square: bool
    component: int


def _build(sec: MehrabianMetricsSection, ctx: BuildContext) -> MehrabianMetrics:
    """Per window: RMS synchronisation / tracking error and RMS control (integrated at the RK stages)
    [rad, N m], effort int sum_j |u_j|^2 dt [(N m)^2 s]; maxima over the step starts t_k in the window of
    the largest link / tracking error norm, the spread (max - min over spacecraft) and |angle| per Euler
    angle [rad]. Appended to the loop's metrics (``ctx.metrics``)."""
    from formation_ftc.sim.metrics import Metric

    dt = ctx.dt
    rms = _Opts(norm=True, square=True)  # RK-stage integrals of |.|^2
    # (name, signal, reduction, window kind, options, spacecraft reduction, units); window kind
    # "stage": integrated over [a, b) at the RK stages, "sample": the step starts t_k in [a, b)
    table: list[tuple[str, str, str, str, _Opts, str, str]] = [
        ("sync_err_rms", "synchronisation_error", "stage_root_mean", "stage", rms, "mean", "rad"),
        ("track_err_rms", "tracking_error", "stage_root_mean", "stage", rms, "mean", "rad"),
        ("control_effort", "command", "stage_integral", "stage", rms, "sum", "N2 m2 s"),
        ("control_rms", "command", "stage_root_mean", "stage", rms, "mean", "N m"),
        ("sync_err_max", "synchronisation_error", "max", "sample", _Opts(norm=True), "max", "rad"),
        ("track_err_max", "tracking_error", "max", "sample", _Opts(norm=True), "max", "rad"),
    ]
    table += [
        (f"spread_max_{ax}", "attitude", "max", "sample", _Opts(component=p), "range", "rad")
        for p, ax in enumerate(AXES)
    ]
    table += [
        (f"abs_max_{ax}", "attitude", "max", "sample", _Opts(component=p, norm=True), "max", "rad")
        for p, ax in enumerate(AXES)
    ]
    for w, (a, b) in clipped_windows(sec, ctx.horizon).items():
        if b - a <= 0:  # window after the horizon (shortened run): no metrics
            continue
        ends = {"stage": as_float(b), "sample": as_float(b - 0.5 * dt)}  # sample: a <= t_k < b
        ctx.metrics.extend(
            Metric(
                f"{name}_{w}",
                signal,
                reduce,
                spacecraft=sc,
                units=units,
                start=as_float(a),
                end=ends[kind],
                **opts,
            )
            for name, signal, reduce, kind, opts, sc, units in table
        )
    return MehrabianMetrics()


register(
    "evaluation",
    "mehrabian-metrics",
    MehrabianMetricsSection,
    _build,
    "Mehrabian's metrics: synchronisation / tracking error, effort, Euler-angle spreads per window",
)
