"""Method ``li2020``: the closed loops of Li et al. 2020 (Thm 1, Thm 2 with delays, SIR-FTC baseline)
as compositions of components.

* plant :class:`~formation_ftc.components.plants.relative_lvlh.RelativeLvlhPlant` (eqs. (1)-(4)) with
  the disturbance h_i(t), about the reference orbit
  :class:`~formation_ftc.components.references.keplerian.KeplerianReference` (its RK4 stage values are
  computed once per step, shared by every spacecraft and every run of a batch);
* sensors: the exact relative state;
* network: :class:`~formation_ftc.components.networks.weighted_graph.GraphNetwork` (Thm 1) or
  :class:`~formation_ftc.components.networks.weighted_graph.DelayedGraphNetwork` (Thm 2: s_j(t - T_ij(t))
  read from a history ring buffer with linear interpolation, constant prehistory s_j(0));
* controller: :class:`~formation_ftc.components.controllers.li2020_adaptive.Li2020AdaptiveController`
  (Thm 1 / Thm 2) or :class:`~formation_ftc.components.controllers.sir_ftc.SirFtcController`, evaluated
  at every RK stage with their adaptive states integrated with the plant;
* actuator: faults F_i = Gamma_i(t) f_i + delta_i(t) (eq. (5)) written as expressions or as a numeric
  step profile (``faults.profile = "step"``, onsets snapped to the step grid);
* evaluation: mu1, mu2 (literal, E000-08) and mu2_vc at every step
  (:class:`~formation_ftc.components.evaluations.formation_errors.FormationErrors`).

Time-only signals (desired formation, sigma_i(t), faults, disturbance, delays) are evaluated once per
step for the three RK stage times; faults and disturbances at the left limit t_{k+1}^- at the last
stage, so that a fault onset on the grid never falls inside a step. Every metric is accumulated at
every step inside the run. ``delta_v`` integrates the commanded ||f_i|| / m_i.
"""

from __future__ import annotations

import numpy as np

from formation_ftc.components.actuators.expression_faults import ExpressionFaultActuator
from formation_ftc.components.actuators.step_faults import StepFaultActuator
from formation_ftc.components.controllers.desired_formation import RotatingFormation
from formation_ftc.components.controllers.li2020_adaptive import Li2020AdaptiveController
from formation_ftc.components.controllers.sir_ftc import SirFtcController
from formation_ftc.components.evaluations.formation_errors import FormationErrors
from formation_ftc.components.networks.weighted_graph import (
    DelayedGraphNetwork,
    GraphNetwork,
    graph_edges,
)
from formation_ftc.components.plants.relative_lvlh import RelativeLvlhPlant
from formation_ftc.components.references.keplerian import KeplerianReference
from formation_ftc.components.sensors.exact_relative_state import ExactRelativeStateSensors
from formation_ftc.core.history import required_capacity
from formation_ftc.core.rotating_formation import chi_from_period, formation_offsets
from formation_ftc.papers.li2020.conditions import check, delay_statistics
from formation_ftc.papers.li2020.figures import plot_scenario
from formation_ftc.papers.li2020.schema import Li2020Scenario
from formation_ftc.registry import Method, register_method
from formation_ftc.sim.compiled import Compiled, compile_loop
from formation_ftc.sim.components import NoNetwork, as_float
from formation_ftc.sim.loop import ClosedLoop
from formation_ftc.sim.metrics import Metric

__all__ = ["build", "make_loop", "metrics_of", "MU1_AT", "E000_04_WINDOW", "METHOD"]

#: times [s] of the mu1_at_<t>s metrics (those within the horizon)
MU1_AT = (10.0, 20.0, 30.0, 100.0, 300.0, 1000.0, 3000.0)
#: window [s] of ``mu1_max_50_300s`` (the E000-04 comparison of the literal and corrected d_hat sign;
#: declared when the horizon reaches its end)
E000_04_WINDOW = (50.0, 300.0)


def _formation(s: Li2020Scenario) -> RotatingFormation:
    fm, o = s.formation, s.orbit
    chi = (
        fm.chi
        if fm.chi is not None
        else chi_from_period(o.period, fm.completion_fraction, fm.completion_residual)
    )
    return RotatingFormation(
        offsets=as_float(formation_offsets(fm.radius, fm.phase)),
        chi=as_float(chi),
        rotation=as_float(fm.rotation),
        growth=as_float(fm.growth),
        centre=as_float(fm.centre_offset),
    )


def _controller(s: Li2020Scenario):
    N = s.spacecraft.count
    c, sir = s.controller, s.sir_ftc
    k = as_float(s.per_spacecraft("k"))
    if c.law == "sir-ftc":
        return SirFtcController(
            count=N,
            formation=_formation(s),
            k=k,
            k0=as_float(sir.k0),
            phi=as_float(sir.phi),
            sigma1=as_float(sir.sigma1),
            sigma2=as_float(sir.sigma2),
            mu_s=as_float(sir.mu_s),
            b_hat0=as_float(np.full(N, sir.b_hat0)),
        )
    literal_sign = c.dhat_sign_literal and c.law == "thm2"
    return Li2020AdaptiveController(
        count=N,
        formation=_formation(s),
        k=k,
        lam=as_float(s.per_spacecraft("lam")),
        gamma=as_float(s.per_spacecraft("gamma")),
        eta=as_float(s.per_spacecraft("eta")),
        adapt_mu=as_float(s.per_spacecraft("mu")),
        upsilon=as_float(s.per_spacecraft("upsilon")),
        m_hat0=as_float(s.per_spacecraft("m_hat0")),
        beta_hat0=as_float(s.per_spacecraft("beta_hat0")),
        d_hat0=as_float(s.per_spacecraft("d_hat0")),
        sigma_a=as_float(s.per_spacecraft("sigma_a")),
        sigma_t0=as_float(c.sigma_t0),
        d_sign=as_float(-1.0 if literal_sign else 1.0),
        mu=as_float(s.orbit.mu),
        sigma_form=c.sigma_form,
    )


def _network(s: Li2020Scenario):
    C = as_float(np.asarray(s.network.adjacency, float))
    if s.controller.law == "thm1":
        return GraphNetwork(weights=C)
    if s.controller.law == "sir-ftc":
        return NoNetwork()
    dt = float(s.simulation.dt)
    edges = graph_edges(s.network.adjacency)
    used = {st.pair: st for st in delay_statistics(s)}
    t_max = max((used[pr].value_max for pr in edges), default=0.0)
    return DelayedGraphNetwork(
        weights=C,
        delays=tuple(tuple(str(x) for x in r) for r in s.network.delays),
        edges=edges,
        capacity=required_capacity(t_max, dt) + 1,
        dt=dt,
        short_delays=False,
    )  # validate_delays: T >= dt on every used link


def _actuator(s: Li2020Scenario):
    f = s.faults
    if f.profile == "step":
        dt = float(s.simulation.dt)
        # onsets snapped to the step grid so that no RK step straddles a fault onset
        onset = np.round(np.asarray(f.step_onset, float) / dt) * dt
        return StepFaultActuator(
            alpha=as_float(f.step_effectiveness), onset=as_float(onset), bias=tuple(f.additive)
        )
    return ExpressionFaultActuator(
        count=s.spacecraft.count,
        effectiveness=tuple(f.effectiveness_texts()),
        bias=tuple(f.additive),
    )


def metrics_of(s: Li2020Scenario) -> tuple[Metric, ...]:
    """The metrics of a ``li2020`` run (every step inside the run)."""
    T = float(s.simulation.horizon)
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
    names = ("b_hat",) if s.controller.law == "sir-ftc" else ("m_hat", "beta_hat", "d_hat")
    units = {"m_hat": "kg", "beta_hat": "1", "d_hat": "N", "b_hat": "N"}
    m += [Metric(f"{n}_final", n, "last", spacecraft="each", units=units[n]) for n in names]
    # value at the step t = 0.9 T (the adaptive parameters' drift over the last 10 % of the horizon)
    m += [
        Metric(f"{n}_at_90pct", n, "at", spacecraft="each", units=units[n], start=as_float(0.9 * T))
        for n in names
    ]
    return tuple(m)


def make_loop(s: Li2020Scenario) -> ClosedLoop:
    """The scenario as a composition of components (every number a leaf, every choice static)."""
    N = s.spacecraft.count
    o = s.orbit
    v0 = (
        np.zeros((N, 3))
        if s.spacecraft.initial_velocity is None
        else np.asarray(s.spacecraft.initial_velocity)
    )
    plant = RelativeLvlhPlant(
        mass=as_float(s.spacecraft.mass),
        initial_state_lvlh=as_float(
            np.hstack([np.asarray(s.spacecraft.initial_position, float), v0])
        ),
        mu=as_float(o.mu),
        disturbance_force=tuple(s.disturbance.force),
    )
    reference = KeplerianReference(
        semi_latus_rectum=as_float(o.semi_latus_rectum),
        eccentricity=as_float(o.eccentricity),
        mu=as_float(o.mu),
        true_anomaly0=as_float(o.true_anomaly0),
    )
    sim = s.simulation
    return ClosedLoop.from_simulation(
        sim,
        plant=plant,
        reference=reference,
        sensors=ExactRelativeStateSensors(count=N),
        network=_network(s),
        controller=_controller(s),
        actuator=_actuator(s),
        metrics=metrics_of(s),
        evaluations=(FormationErrors(),),
    )


def build(s: Li2020Scenario) -> Compiled:
    """Compile a ``li2020`` scenario (see module docstring)."""
    return compile_loop(make_loop(s))


METHOD = register_method(
    Method(
        name="li2020",
        schema=Li2020Scenario,
        build=build,
        description="Li2020 nonlinear elliptic relative motion, adaptive FTC (Thm 1 / Thm 2 with delays) or SIR-FTC",
        check=check,
        plot=plot_scenario,
    )
)
