"""Method ``gui2022``: ILO fault reconstruction and LOF2TC / COF2TC formation keeping (Gui et al. 2022).

A composition of components (:func:`make_loop`)::

    plant       ZohClohessyWiltshirePlant     q_dot = A q + B (a + d(t)), exact ZOH step     (1)-(3)
    actuator    ThrusterBiasFaultActuator     a = u + F(t)  (thruster bias faults, H = B)
    sensors     ExactRelativeStateSensors     y = C q, C = I6
    estimator   IterativeLearningObserver     F_hat_k, q_hat_k                                 (5)
    controller  LearningOutputFeedback...     u_k from e_y = q0(t_k) - y_k, F_hat_k           (30)-(32)
                (or ConventionalOutputFeedback... u = K e_y, or FreeDrift u = 0)

One step k (t_k = k dt): measure y_k; ILO learning update F_hat_k; sampled controller u_k; plant
``q_{k+1} = Ad q_k + Bd (u_k + F(t_k) + d(t_k))``; ILO time update (forward Euler with u_k, F_hat_k held).
The nominal orbit q0(t) (28) is the CW closed form evaluated at t_k (no drift). Fault onsets are snapped
to the step grid. Metrics are accumulated at every step inside the run (windows over the steps
k < n unless stated; final values at the horizon).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from formation_ftc.blocks.observers.iterative_learning_observer import learning_steps
from formation_ftc.components.actuators.thruster_bias import ThrusterBiasFaultActuator
from formation_ftc.components.controllers.output_feedback import (
    ConventionalOutputFeedbackController,
    FreeDrift,
    LearningOutputFeedbackController,
)
from formation_ftc.components.estimators.iterative_learning_observer import (
    IterativeLearningObserver,
)
from formation_ftc.components.evaluations.signal_arithmetic import PartNorm, SignalSum
from formation_ftc.components.plants.clohessy_wiltshire_zoh import (
    STATE_COMPONENTS,
    ZohClohessyWiltshirePlant,
)
from formation_ftc.components.sensors.exact_relative_state import ExactRelativeStateSensors
from formation_ftc.core.dynamics.cw import cw_matrices
from formation_ftc.papers.gui2022.conditions import care_cached, check, gains_of, lmi_design_cached
from formation_ftc.papers.gui2022.figures import plot
from formation_ftc.papers.gui2022.schema import Gui2022Scenario
from formation_ftc.registry import Method, register_method
from formation_ftc.sim.compiled import Compiled, compile_loop
from formation_ftc.sim.components import as_float
from formation_ftc.sim.loop import ClosedLoop
from formation_ftc.sim.metrics import Metric

__all__ = [
    "make_loop",
    "build",
    "metrics_of",
    "gains_of",
    "lmi_design_cached",
    "care_cached",
    "METHOD",
    "COMPONENTS",
    "AXES",
    "LOWPASS_WINDOW",
    "ESTIMATE_ERROR_AT",
    "lowpass_steps",
]

COMPONENTS = list(STATE_COMPONENTS)
AXES = ["x", "y", "z"]
N_DEPUTIES = 1
#: boxcar of the low-pass metrics [s]: F - F_hat (and v - h) averaged over consecutive blocks of this
#: length before the RMS (``block_rms``); the deviation of F_hat from its block mean measures the chatter
#: (``block_dev_rms``). Fixed, independent of ``simulation.record_every``.
LOWPASS_WINDOW = 0.1
#: times [s] of the exact samples ``estimate_pos_err_at_<t>s`` of ||q - q_hat|| (position part)
ESTIMATE_ERROR_AT = (0.0, 1.0, 2.0)


def lowpass_steps(dt: float) -> int:
    """Steps of the boxcar: LOWPASS_WINDOW / dt rounded to an even number >= 2 (an even boxcar removes a
    chatter of period 2 steps exactly)."""
    return max(2, 2 * round(LOWPASS_WINDOW / dt / 2))


def _per_axis(values, n: int = N_DEPUTIES):
    """(3,) -> (n, 3) float64 leaf."""
    return as_float(np.broadcast_to(np.asarray(values, dtype=float), (n, 3)).copy())


def _actuator(s: Gui2022Scenario) -> ThrusterBiasFaultActuator:
    """Faults of Sec. 5: steps on x, y; 0.25 sin(0.05 t + pi/4) - 0.2 e^{-0.1 t} on z (onsets snapped)."""
    dt, f = s.simulation.dt, s.faults
    onset = [round(t / dt) * dt for t in (f.x_onset, f.y_onset, f.z_onset)]
    return ThrusterBiasFaultActuator(
        count=N_DEPUTIES,
        onset=_per_axis(onset),
        magnitude=_per_axis([f.x_magnitude, f.y_magnitude, 0.0]),
        amplitude=_per_axis([0.0, 0.0, f.z_amplitude]),
        omega=_per_axis([0.0, 0.0, f.z_omega]),
        phase=_per_axis([0.0, 0.0, f.z_phase]),
        decay_amplitude=_per_axis([0.0, 0.0, f.z_decay_amplitude]),
        decay_rate=_per_axis([0.0, 0.0, f.z_decay_rate]),
        decay_origin=_per_axis([0.0, 0.0, onset[2] if f.z_decay_shifted else 0.0]),  # E002-09
        units="m s-2",
    )


def _controller(s: Gui2022Scenario, K):
    c, n = s.controller, s.orbit.mean_motion
    if c.law == "none":
        return FreeDrift(count=N_DEPUTIES)
    _, B = cw_matrices(n)
    Bp = np.linalg.pinv(B)  # B^+ = (B^T B)^-1 B^T
    common: dict[str, Any] = dict(
        count=N_DEPUTIES,
        mean_motion=as_float(n),
        desired_initial=as_float(np.asarray(s.initial.desired_state, dtype=float)[None, :]),
        K=as_float(K),
        BpH=as_float(Bp @ B),
    )
    if c.law == "cof2tc":
        return ConventionalOutputFeedbackController(
            **common, fault_compensation=c.fault_compensation
        )
    return LearningOutputFeedbackController(
        **common,
        G1=as_float(c.G1),
        G2=as_float(c.G2),
        G3=as_float(c.G3),
        G4=as_float(c.G4),
        BpE=as_float(Bp @ B),
        pi_initial=as_float(np.full(N_DEPUTIES, c.pi_initial)),
        v_initial=_per_axis(c.v_initial),
        learning_steps=learning_steps(
            c.learning_interval, s.simulation.dt, "controller.learning_interval"
        ),
    )


def metrics_of(s: Gui2022Scenario) -> tuple[Metric, ...]:
    """The paper's metrics, accumulated at every step k < n (final values at the horizon sample)."""
    dt, n_steps = s.simulation.dt, s.simulation.n_steps
    f, mt = s.faults, s.metrics

    def ks(t):
        return round(t / dt)

    def at(k):
        return float(k * dt)

    last = (n_steps - 0.5) * dt  # window end that excludes the horizon sample
    onset = [ks(f.x_onset), ks(f.y_onset), ks(f.z_onset)]
    k_rms = [k + ks(mt.fault_rms_delay) for k in onset]
    acc = "m s-2"
    out = []
    for i, ax in enumerate(AXES):
        err: dict[str, Any] = dict(
            signal="fault_error", component=i, norm=True, spacecraft="max", units=acc, end=last
        )
        out += [
            Metric(f"fault_rms_err_{ax}", reduce="rms", start=at(k_rms[i]), **err),
            Metric(
                f"fault_settle_time_{ax}",
                reduce="settle_delay",
                start=at(onset[i]),
                threshold=mt.settle_threshold,
                **{**err, "units": "s"},
            ),
            Metric(
                f"fault_max_err_after_1s_{ax}", reduce="max", start=at(onset[i] + ks(1.0)), **err
            ),
            Metric(
                f"final_fault_err_{ax}",
                "fault_error",
                reduce="final",
                component=i,
                spacecraft="max",
                units=acc,
            ),
        ]
    for c, name in enumerate(COMPONENTS):
        out.append(
            Metric(
                f"sign_mean_{name}",
                "estimation_error_sign",
                reduce="mean",
                component=c,
                spacecraft="mean",
                start=at(k_rms[c % 3]),
                end=last,
            )
        )
    out.append(
        Metric(
            "estimate_max_err_after_start",
            "estimation_error",
            reduce="max",
            norm=True,
            spacecraft="max",
            units="1",
            start=at(ks(mt.estimate_start)),
            end=(ks(mt.estimate_end) - 0.5) * dt,
        )
    )
    # low-pass (boxcar of lowpass_steps) RMS of F - F_hat per axis over the fault_rms window, and the RMS
    # of F_hat about its boxcar mean (the chatter) from fault_rms_delay to the x fault onset
    box = lowpass_steps(dt)
    for i, ax in enumerate(AXES):
        out += [
            Metric(
                f"fault_lowpass_rms_err_{ax}",
                "fault_error",
                reduce="block_rms",
                component=i,
                spacecraft="max",
                units=acc,
                start=at(k_rms[i]),
                end=last,
                block=box,
            ),
            Metric(
                f"fault_estimate_chatter_rms_{ax}",
                "fault_estimate",
                reduce="block_dev_rms",
                component=i,
                spacecraft="max",
                units=acc,
                start=at(ks(mt.fault_rms_delay)),
                end=(onset[0] - 0.5) * dt,
                block=box,
            ),
        ]
    out += [
        Metric(
            f"estimate_pos_err_at_{tq:g}s",
            "estimation_position_error",
            reduce="at",
            spacecraft="max",
            units="m",
            start=at(ks(tq)),
        )
        for tq in ESTIMATE_ERROR_AT
        if ks(tq) <= n_steps
    ]
    if s.controller.law != "none":
        pos: dict[str, Any] = dict(signal="position_tracking_error", spacecraft="max", units="m")
        out += [
            Metric("pos_rms", reduce="rms", start=at(ks(mt.position_rms_start)), end=last, **pos),
            Metric("pos_max_after_fault", reduce="max", start=at(onset[0]), end=last, **pos),
            Metric(
                "ex_max_fault_window",
                "tracking_error",
                reduce="max",
                component=0,
                norm=True,
                spacecraft="max",
                units="m",
                start=at(onset[0]),
                end=(onset[2] - 0.5) * dt,
            ),
            Metric(
                "ez_max_after",
                "tracking_error",
                reduce="max",
                component=2,
                norm=True,
                spacecraft="max",
                units="m",
                start=at(ks(mt.z_amplitude_start)),
                end=last,
            ),
            Metric(
                "pos_settle_time_0p01",
                reduce="settle",
                threshold=0.01,
                end=last,
                **{**pos, "units": "s"},
            ),
            Metric("final_pos_err", reduce="final", **pos),
            Metric(
                "final_vel_err",
                "velocity_tracking_error",
                reduce="final",
                spacecraft="max",
                units="m s-1",
            ),
        ]
        if s.controller.law == "lof2tc":
            out.append(Metric("pi_max", "learning_gain", reduce="max", spacecraft="max", end=last))
            # Fig. 10: low-pass RMS per axis of v - h and of h = d + F - F_hat from position_rms_start
            for i, ax in enumerate(AXES):
                out += [
                    Metric(
                        f"{sig}_lowpass_rms_{ax}",
                        sig,
                        reduce="block_rms",
                        component=i,
                        spacecraft="max",
                        units=acc,
                        start=at(ks(mt.position_rms_start)),
                        end=last,
                        block=box,
                    )
                    for sig in ("compensation_error", "synthesized_disturbance")
                ]
    return tuple(out)


def _evaluations(s: Gui2022Scenario) -> tuple:
    acc = "m s-2"
    out: list[SignalSum | PartNorm] = [
        SignalSum(
            "fault_error",
            (("+", "fault"), ("-", "fault_estimate")),
            units=acc,
            long_name="e_F = F - F_hat",
        ),
        SignalSum(
            "synthesized_disturbance",
            (("+", "disturbance"), ("+", "fault"), ("-", "fault_estimate")),
            units=acc,
            long_name="h = d + e_F (33)",
        ),
        SignalSum(
            "synthesized_disturbance_mean",
            (("+", "disturbance"), ("+", "fault"), ("-", "fault_estimate_mean")),
            units=acc,
            long_name="h = d + F - mean(F_hat) over the record interval",
        ),
    ]
    out.append(
        PartNorm(
            "estimation_position_error",
            "estimation_error",
            0,
            3,
            units="m",
            long_name="||q - q_hat position part|| of the ILO",
        )
    )
    if s.controller.law == "lof2tc":
        out.append(
            SignalSum(
                "compensation_error",
                (("+", "compensation"), ("-", "synthesized_disturbance")),
                units=acc,
                long_name="v - h, h = d + e_F (33)",
            )
        )
    if s.controller.law != "none":
        out += [
            PartNorm(
                "position_tracking_error",
                "tracking_error",
                0,
                3,
                units="m",
                long_name="||e_y position part||",
            ),
            PartNorm(
                "velocity_tracking_error",
                "tracking_error",
                3,
                6,
                units="m s-1",
                long_name="||e_y velocity part||",
            ),
        ]
    return tuple(out)


def make_loop(s: Gui2022Scenario) -> ClosedLoop:
    """The scenario as a composition of components (every number a leaf, every choice static)."""
    sim, o = s.simulation, s.observer
    n = s.orbit.mean_motion
    g = gains_of(s)
    q_init = np.asarray(s.initial.state, dtype=float)[None, :]
    plant = ZohClohessyWiltshirePlant(
        mean_motion=as_float(n),
        initial_state_lvlh=as_float(q_init),
        disturbance_amplitude=as_float(s.disturbance.amplitude),
    )
    estimator = IterativeLearningObserver(
        count=N_DEPUTIES,
        mean_motion=as_float(n),
        L1=as_float(g["L1"]),
        L2=as_float(g["L2"]),
        Q1=as_float(o.Q1),
        Q2=as_float(o.Q2),
        gamma=as_float(o.gamma),
        initial_estimate=as_float(
            np.asarray(o.initial_estimate, dtype=float)[None, :]
        ),  # stated, not q(0)
        fault_prehistory=as_float(np.zeros((N_DEPUTIES, 3))),
        learning_steps=learning_steps(o.learning_interval, sim.dt, "observer.learning_interval"),
        sign_term=o.sign_term,
        mean_steps=sim.record_every,
    )
    return ClosedLoop.from_simulation(
        sim,
        plant=plant,
        controller=_controller(s, g["K"]),
        sensors=ExactRelativeStateSensors(count=N_DEPUTIES),
        estimator=estimator,
        actuator=_actuator(s),
        metrics=metrics_of(s),
        evaluations=_evaluations(s),
    )


def build(s: Gui2022Scenario) -> Compiled:
    """Compile a gui2022 scenario (see module docstring)."""
    return compile_loop(make_loop(s))


METHOD = register_method(
    Method(
        name="gui2022",
        schema=Gui2022Scenario,
        build=build,
        description="Gui2022: CW deputy, iterative learning observer (5), LOF2TC (30)-(32) / COF2TC baseline",
        check=check,
        plot=plot,
    )
)
