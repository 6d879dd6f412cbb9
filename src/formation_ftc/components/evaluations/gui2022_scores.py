"""Evaluation ``gui2022-scores``: Gui2022's evaluation signals and metric set (its Sec. 5).

Signals: the synthesized disturbance h = d + e_F (33) and its record-interval mean, the position part
of the ILO's estimation error ||q - q_hat|| and, with LOF2TC, v - h. Metrics (accumulated at every step
inside the run; windows after the ``thruster-bias`` onsets): the fault reconstruction (RMS, settling,
low-pass RMS and chatter per axis), the estimation error, and with an output-feedback law its
tracking (RMS, maxima, settling, final errors; LOF2TC: pi and the low-pass v - h and h).

Needs the ILO's records (``thruster-fault-estimate``), the thruster faults (``thruster-bias-faults``)
and the plant's perturbation (``perturbation-signal``, plant ``clohessy-wiltshire-zoh``).
"""

from __future__ import annotations

from functools import partial

import numpy as np

from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.components.evaluations._signal_arithmetic import PartNorm, SignalSum
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import component

__all__ = ["Gui2022Scores", "ScoresSection", "lowpass_steps", "LOWPASS_WINDOW", "ESTIMATE_ERROR_AT"]

#: boxcar of the low-pass metrics [s]: F - F_hat (and v - h) averaged over consecutive blocks of this
#: length before the RMS (``block_rms``); the deviation of F_hat from its block mean measures the
#: chatter (``block_dev_rms``). Fixed, independent of ``simulation.record_every``.
LOWPASS_WINDOW = 0.1
#: times [s] of the exact samples ``estimate_pos_err_at_<t>s`` of ||q - q_hat|| (position part)
ESTIMATE_ERROR_AT = (0.0, 1.0, 2.0)
ACC = "m s-2"


def lowpass_steps(dt: float) -> int:
    """Steps of the low-pass boxcar: LOWPASS_WINDOW / dt rounded to an even number >= 2 (an even boxcar
    removes a chatter of period 2 steps exactly).

    Parameters
    ----------
    dt : float
        Step [s].

    Returns
    -------
    int
        Boxcar length [steps].

    Examples
    --------
    >>> lowpass_steps(0.001), lowpass_steps(0.2)
    (100, 2)
    """
    return max(2, 2 * round(LOWPASS_WINDOW / dt / 2))


@component
class Gui2022Scores(PartNorm):
    """``estimation_position_error`` = ||position part of q - q_hat|| of the ILO (a
    :class:`~formation_ftc.components.evaluations._signal_arithmetic.PartNorm`); declares what the
    paper's metric set reads."""

    def needs(self) -> dict[str, str]:
        return {
            "thruster-fault-estimate": "score the ILO's estimate, output error and fault estimate",
            "thruster-bias-faults": "score the reconstruction after their onsets",
            "perturbation-signal": "form h = d + e_F (33)",
        }


class ScoresSection(StrictModel):
    """Gui2022's evaluation signals and metric set (Sec. 5): windows of the metrics accumulated at every
    step inside the run (the fault onsets are the ``thruster-bias`` actuator's)."""

    fault_rms_delay: float = builder_input(
        100.0, ge=0, description="RMS of F - F_hat per axis from that axis' onset + this delay [s]."
    )
    position_rms_start: float = builder_input(
        1600.0, ge=0, description="RMS of ||e_pos|| (and Fig. 10's v - h, h) from this time [s]."
    )
    settle_threshold: float = builder_input(
        0.01, gt=0, description="|F - F_hat| threshold of the settling-time metric [m/s^2]."
    )
    estimate_start: float = builder_input(
        10.0, ge=0, description="max ||q - q_hat|| of the observer from this time [s] ..."
    )
    estimate_end: float = builder_input(
        1500.0, ge=0, description="... up to this time (before the first fault) [s]."
    )
    z_amplitude_start: float = builder_input(
        2100.0, ge=0, description="max |e_z| tracking error from this time [s]."
    )


def _scores_metrics(
    sec: ScoresSection, ctx: BuildContext, onset_s, tracks: bool, learns: bool
) -> list:
    """The paper's metrics, accumulated at every step k < n (final values at the horizon sample);
    ``onset_s`` the fault onsets per axis [s]; ``tracks``: the law records its tracking error (an
    output-feedback law), ``learns``: and its learning gain and compensation (LOF2TC)."""
    from formation_ftc.sim.metrics import Metric

    sim = ctx.scenario.simulation
    dt, n_steps = ctx.dt, sim.n_steps

    def ks(t):
        return round(t / dt)

    def at(k):
        return float(k * dt)

    last = (n_steps - 0.5) * dt  # window end that excludes the horizon sample
    position_start = at(ks(sec.position_rms_start))
    onset = [ks(t) for t in onset_s]
    k_rms = [k + ks(sec.fault_rms_delay) for k in onset]
    worst = partial(Metric, spacecraft="max")  # the worst spacecraft
    accel = partial(worst, units=ACC)
    # low-pass (boxcar of lowpass_steps) RMS per axis
    lowpass = partial(accel, reduce="block_rms", end=last, block=lowpass_steps(dt))
    out = []
    for i, ax in enumerate("xyz"):
        err = partial(accel, signal="fault_error", component=i, norm=True, end=last)
        out += [
            err(f"fault_rms_err_{ax}", reduce="rms", start=at(k_rms[i])),
            err(
                f"fault_settle_time_{ax}",
                reduce="settle_delay",
                start=at(onset[i]),
                threshold=sec.settle_threshold,
                units="s",
            ),
            err(f"fault_max_err_after_1s_{ax}", reduce="max", start=at(onset[i] + ks(1.0))),
            accel(f"final_fault_err_{ax}", "fault_error", reduce="final", component=i),
        ]
    sign = partial(Metric, signal="estimation_error_sign", reduce="mean", spacecraft="mean")
    out += [
        sign(f"sign_mean_{name}", component=c, start=at(k_rms[c % 3]), end=last)
        for c, name in enumerate(("x", "y", "z", "vx", "vy", "vz"))
    ]
    out.append(
        worst(
            "estimate_max_err_after_start",
            "estimation_error",
            reduce="max",
            norm=True,
            units="1",
            start=at(ks(sec.estimate_start)),
            end=(ks(sec.estimate_end) - 0.5) * dt,
        )
    )
    # F - F_hat over the fault_rms window, and the RMS of F_hat about its boxcar mean (the chatter) from
    # fault_rms_delay to the x fault onset
    for i, ax in enumerate("xyz"):
        out += [
            lowpass(f"fault_lowpass_rms_err_{ax}", "fault_error", component=i, start=at(k_rms[i])),
            lowpass(
                f"fault_estimate_chatter_rms_{ax}",
                "fault_estimate",
                reduce="block_dev_rms",
                component=i,
                start=at(ks(sec.fault_rms_delay)),
                end=(onset[0] - 0.5) * dt,
            ),
        ]
    estimate_at = partial(worst, signal="estimation_position_error", reduce="at", units="m")
    out += [
        estimate_at(f"estimate_pos_err_at_{tq:g}s", start=at(ks(tq)))
        for tq in ESTIMATE_ERROR_AT
        if ks(tq) <= n_steps
    ]
    if not tracks:
        return out
    pos = partial(worst, signal="position_tracking_error", units="m")
    axis = partial(worst, signal="tracking_error", reduce="max", norm=True, units="m")
    out += [
        pos("pos_rms", reduce="rms", start=position_start, end=last),
        pos("pos_max_after_fault", reduce="max", start=at(onset[0]), end=last),
        axis("ex_max_fault_window", component=0, start=at(onset[0]), end=(onset[2] - 0.5) * dt),
        axis("ez_max_after", component=2, start=at(ks(sec.z_amplitude_start)), end=last),
        pos("pos_settle_time_0p01", reduce="settle", threshold=0.01, end=last, units="s"),
        pos("final_pos_err", reduce="final"),
        worst("final_vel_err", "velocity_tracking_error", reduce="final", units="m s-1"),
    ]
    if learns:
        out.append(worst("pi_max", "learning_gain", reduce="max", end=last))
        # Fig. 10: low-pass RMS per axis of v - h and of h = d + F - F_hat from position_rms_start
        for i, ax in enumerate("xyz"):
            out += [
                lowpass(f"{sig}_lowpass_rms_{ax}", sig, component=i, start=position_start)
                for sig in ("compensation_error", "synthesized_disturbance")
            ]
    return out


def _build(sec: ScoresSection, ctx: BuildContext) -> Gui2022Scores:
    """Gui2022's signals h = d + e_F (33), its record-interval mean, ||position part of q - q_hat|| and,
    with LOF2TC, v - h; the paper's metric set goes to ``ctx.metrics`` (the law's metrics after what
    the ``[controller]`` section says it is; the fault onsets are the ``[actuator]``'s, 0 without
    them: the loop is then refused for the missing ``thruster-bias-faults``)."""
    law = ctx.section("controller")
    # by the fields the law states: a nominal orbit it tracks (the Gui2022 output-feedback laws) and a
    # learning interval (LOF2TC)
    tracks = hasattr(law, "desired_state") and hasattr(law, "care_q_scale")
    learns = tracks and hasattr(law, "learning_interval")
    onsets = np.asarray(getattr(ctx.section("actuator"), "onset", 0.0), dtype=float)
    onset_s = np.broadcast_to(onsets, (ctx.count, 3)).min(axis=0)  # earliest per axis [s]
    ctx.metrics.extend(_scores_metrics(sec, ctx, onset_s, tracks, learns))
    h = (("+", "disturbance"), ("+", "fault"))
    h_mean = "h = d + F - mean(F_hat) over the record interval"
    ctx.evaluations.extend(
        SignalSum(name, (*h, ("-", estimate)), units=ACC, long_name=long_name)
        for name, estimate, long_name in (
            ("synthesized_disturbance", "fault_estimate", "h = d + e_F (33)"),
            ("synthesized_disturbance_mean", "fault_estimate_mean", h_mean),
        )
    )
    if learns:
        v_minus_h = (("+", "compensation"), ("-", "synthesized_disturbance"))
        long_name = "v - h, h = d + e_F (33)"
        ctx.evaluations.append(
            SignalSum("compensation_error", v_minus_h, units=ACC, long_name=long_name)
        )
    name, long_name = "estimation_position_error", "||q - q_hat position part|| of the ILO"
    return Gui2022Scores(name, "estimation_error", 0, 3, units="m", long_name=long_name)


register(
    "evaluation",
    "gui2022-scores",
    ScoresSection,
    _build,
    "Gui2022 Sec. 5 signals (h = d + e_F, v - h, ||q - q_hat||) and metric set (needs the ILO, "
    "thruster-bias faults and the plant's d)",
)
