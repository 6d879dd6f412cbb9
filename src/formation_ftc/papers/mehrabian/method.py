"""Method ``mehrabian``: m spacecraft attitudes as networked EL systems (Mehrabian et al. (1)-(2), (27)-(28))
under the distributed H-infinity law (6)/(8) with adaptive fault recovery (18)-(19) fed by an imperfect
FDI, as a composition of components:

* plant :class:`~formation_ftc.components.plants.euler_angle_attitude.EulerAngleAttitudePlant` -- rigid
  bodies in Euler angles with the true (perturbed) inertia and the held Gaussian input disturbance;
  the true inertias are drawn about ``formation.nominal_inertia``, while the law's model J^ is the
  stated ``controller.nominal_inertia``;
* actuator :class:`~formation_ftc.components.actuators.additive_faults.HeldAdditiveFaultActuator` --
  the true additive faults u_bar (2), sampled at t_k and held over the step;
* estimator :class:`~formation_ftc.components.estimators.fdi_imperfections.ScriptedFdi` -- the FDI
  report (flag, u*) with detection / isolation / identification imperfections (none when the FDI is
  disabled or there is no fault);
* controller :class:`~formation_ftc.components.controllers.networked_el_hinf.NetworkedElHinfController`
  -- continuous, evaluated at every RK stage, reads the measured attitudes of the whole formation
  (ideal, undelayed communication over the graph); perfect sensors.

Randomness: everything random is drawn inside the run from the scenario seed (a leaf of the plant and
of the FDI, and ``ClosedLoop.seed``): ``run_key(seed)`` is split into (initial attitudes, inertia,
disturbance, FDI noise); per-step keys are ``fold_in(key, k)``.

Metrics (every step, inside the run), for each window (fault window, whole run, assessment window;
clipped to the horizon): RMS synchronisation error over the links and RMS tracking error
(``sqrt(1/T int mean |.|^2 dt)``, integrated with the plant at the RK stages) [rad], control effort
``int sum_j |u_j|^2 dt`` [(N m)^2 s] and its RMS per spacecraft [N m]; maxima over the samples at the
starts of the steps inside the window (``start <= t_k < end``): largest link / tracking error norm,
spread (max - min over spacecraft) and largest |angle| per Euler angle [rad].
"""

from __future__ import annotations

import dataclasses
from typing import Any, cast

import jax.numpy as jnp
import numpy as np

from formation_ftc.blocks.fdi import fdi_params, isolation_routing
from formation_ftc.components.actuators.additive_faults import HeldAdditiveFaultActuator
from formation_ftc.components.controllers.networked_el_hinf import NetworkedElHinfController
from formation_ftc.components.estimators.fdi_imperfections import ScriptedFdi
from formation_ftc.components.plants.euler_angle_attitude import AXES, EulerAngleAttitudePlant
from formation_ftc.core import graph as graphs
from formation_ftc.papers.mehrabian import conditions
from formation_ftc.papers.mehrabian.schema import MehrabianScenario
from formation_ftc.registry import Method, register_method
from formation_ftc.sim.compiled import Compiled, compile_loop
from formation_ftc.sim.components import NoEstimator, as_float
from formation_ftc.sim.loop import ClosedLoop
from formation_ftc.sim.metrics import Metric

__all__ = [
    "build",
    "make_loop",
    "with_seed",
    "metric_windows",
    "WINDOWS",
    "AXES",
    "neighbour_pairs",
    "METHOD",
]

#: Metric windows, in this order.
WINDOWS = ("fault_window", "run", "assessment_window")


def neighbour_pairs(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each undirected link once (j < n), 0-based index arrays."""
    j, n = np.nonzero(np.triu(np.asarray(A) > 0, 1))
    return j, n


def metric_windows(s: MehrabianScenario) -> dict[str, tuple[float, float]]:
    """The metric windows [s], clipped to the horizon (a shortened run clips its windows)."""
    H = s.simulation.horizon
    raw = {
        "fault_window": s.metrics.fault_window,
        "run": (0.0, H),
        "assessment_window": s.metrics.assessment_window,
    }
    return {w: (min(float(a), H), min(float(b), H)) for w, (a, b) in raw.items()}


def _metrics(s: MehrabianScenario) -> tuple[Metric, ...]:
    dt = s.simulation.dt
    out: list[Metric] = []
    for w, (a, b) in metric_windows(s).items():
        if b - a <= 0:  # window after the horizon (shortened run): no metrics
            continue
        stage: dict[str, Any] = dict(start=as_float(a), end=as_float(b))
        sample: dict[str, Any] = dict(
            start=as_float(a), end=as_float(b - 0.5 * dt)
        )  # samples t_k with a <= t_k < b
        out += [
            Metric(
                f"sync_err_rms_{w}",
                "synchronisation_error",
                "stage_root_mean",
                norm=True,
                square=True,
                spacecraft="mean",
                units="rad",
                **stage,
            ),
            Metric(
                f"track_err_rms_{w}",
                "tracking_error",
                "stage_root_mean",
                norm=True,
                square=True,
                spacecraft="mean",
                units="rad",
                **stage,
            ),
            Metric(
                f"control_effort_{w}",
                "command",
                "stage_integral",
                norm=True,
                square=True,
                spacecraft="sum",
                units="N2 m2 s",
                **stage,
            ),
            Metric(
                f"control_rms_{w}",
                "command",
                "stage_root_mean",
                norm=True,
                square=True,
                spacecraft="mean",
                units="N m",
                **stage,
            ),
            Metric(
                f"sync_err_max_{w}",
                "synchronisation_error",
                "max",
                norm=True,
                spacecraft="max",
                units="rad",
                **sample,
            ),
            Metric(
                f"track_err_max_{w}",
                "tracking_error",
                "max",
                norm=True,
                spacecraft="max",
                units="rad",
                **sample,
            ),
        ]
        out += [
            Metric(
                f"spread_max_{ax}_{w}",
                "attitude",
                "max",
                component=p,
                spacecraft="range",
                units="rad",
                **sample,
            )
            for p, ax in enumerate(AXES)
        ]
        out += [
            Metric(
                f"abs_max_{ax}_{w}",
                "attitude",
                "max",
                component=p,
                norm=True,
                spacecraft="max",
                units="rad",
                **sample,
            )
            for p, ax in enumerate(AXES)
        ]
    return tuple(out)


def make_loop(s: MehrabianScenario) -> ClosedLoop:
    """The scenario as a composition of components (every number a leaf, every choice static)."""
    m, nch = s.formation.n_spacecraft, 3
    dt = float(s.simulation.dt)
    A = s.formation.adjacency()
    pj, pn = neighbour_pairs(A)
    seed = jnp.asarray(s.simulation.seed, dtype=jnp.uint32)
    ones = np.ones((m, nch))
    q0_fixed = (
        np.deg2rad(np.asarray(s.initial.attitude_deg, dtype=float))
        if s.initial.attitude_deg
        else np.zeros((m, nch))
    )
    qdot0 = (
        np.deg2rad(np.asarray(s.initial.rate_deg_s, dtype=float))
        if s.initial.rate_deg_s
        else np.zeros((m, nch))
    )
    plant = EulerAngleAttitudePlant(
        seed=seed,
        random_initial=as_float(1.0 if s.initial.random else 0.0),
        q0_range=as_float(np.deg2rad(s.initial.attitude_range_deg)),
        q0_fixed=as_float(q0_fixed),
        qdot0=as_float(qdot0),
        J_nominal=as_float(np.tile(np.asarray(s.formation.nominal_inertia), (m, 1))),
        inertia_spread=as_float(s.formation.inertia_uncertainty),
        disturbance_std=as_float(np.sqrt(s.disturbance.variance)),
        step=dt,
    )

    faults: dict[str, Any] = dict(
        torques=tuple(str(f.torque) for f in s.faults),
        spacecraft=tuple(f.spacecraft - 1 for f in s.faults),
        channels=tuple(f.channel - 1 for f in s.faults),
        step=dt,
    )
    windows = as_float(np.array([(f.start, f.end) for f in s.faults]).reshape(-1, 2))
    actuator = HeldAdditiveFaultActuator(count=m, windows=windows, **faults)
    if s.fdi.enabled and s.faults:
        mask = np.zeros((m, nch))
        for f in s.faults:
            mask[f.spacecraft - 1, f.channel - 1] = 1.0
        routing = isolation_routing(
            m,
            nch,
            {
                (e.spacecraft - 1, e.channel - 1): (
                    e.reported_spacecraft - 1,
                    e.reported_channel - 1,
                )
                for e in s.fdi.isolation
            },
        )
        params = fdi_params(
            m,
            nch,
            fault_mask=mask,
            onset=min(f.start for f in s.faults),
            delay=s.fdi.delay,
            detected=s.fdi.detected,
            scale=s.fdi.scale,
            bias=s.fdi.bias,
            noise_std=s.fdi.noise_std,
            routing=routing,
        )
        estimator: ScriptedFdi | NoEstimator = ScriptedFdi(
            count=m, seed=seed, windows=windows, params=params, **faults
        )
    else:
        estimator = NoEstimator()

    c = s.controller
    controller = NetworkedElHinfController(
        count=m,
        K=as_float(c.K * ones),
        K_P=as_float(c.K_P * ones),
        K_I=as_float(c.K_I * ones),
        sigma=as_float(c.sigma * ones),
        e_gain=as_float(c.e_gain * ones),
        alpha=as_float(c.alpha * np.ones(m)),
        gamma=as_float(c.gamma * np.ones(m)),
        phi_b=as_float(c.boundary_layer),
        avg=as_float(graphs.row_normalized(A)),
        J_hat=as_float(
            np.stack([np.diag(c.nominal_inertia)] * m)
        ),  # the law's stated model, not the truth's
        law=c.law,
        compensation=c.compensation,
        desired_attitude=cast(tuple[str, str, str], tuple(str(x) for x in s.desired.attitude)),
        links=tuple((int(a), int(b)) for a, b in zip(pj, pn, strict=True)),
    )
    sim = s.simulation
    return ClosedLoop.from_simulation(
        sim,
        plant=plant,
        controller=controller,
        estimator=estimator,
        actuator=actuator,
        metrics=_metrics(s),
    )


def with_seed(loop: ClosedLoop, seed: int) -> ClosedLoop:
    """The same loop with every seed leaf (plant, FDI, loop) set to ``seed``."""
    sd = jnp.asarray(seed, dtype=jnp.uint32)
    est = loop.estimator
    if isinstance(est, ScriptedFdi):
        est = dataclasses.replace(est, seed=sd)
    plant = dataclasses.replace(loop.plant, seed=sd)  # type: ignore[type-var]  # every plant is a @component
    return dataclasses.replace(loop, plant=plant, estimator=est, seed=sd)


def build(s: MehrabianScenario) -> Compiled:
    """Compile a scenario (see the module docstring)."""
    return compile_loop(make_loop(s))


def _plot(ds, scenario, out_dir):
    from formation_ftc.papers.mehrabian.figures import plot_scenario

    return plot_scenario(ds, scenario, out_dir)


METHOD = register_method(
    Method(
        name="mehrabian",
        schema=MehrabianScenario,
        build=build,
        description="Networked EL spacecraft attitudes: distributed H-infinity sync law (8) with adaptive "
        "fault recovery (18)-(19) under FDI imperfections (Mehrabian et al.)",
        check=conditions.check,
        plot=_plot,
    )
)
