"""Method ``yang2013``: the state-varying switched formation of Yang et al. 2013 as a composition.

The feedback-linearising laws (12)-(13) cancel the known drift terms Phi_i, Upsilon_i of the relative
dynamics (2), (5) exactly (E001-02), so the closed-loop error dynamics of every spacecraft are exact
for any orbit; the loop simulates them at the error level. Components (:func:`make_loop`):

* plant -- :class:`~formation_ftc.components.plants.switched_formation.SwitchedFormationPlant`: N_max
  spacecraft slots with the error dynamics (2), (5) (attitude part a
  :class:`~formation_ftc.components.plants.quaternion_rigid_body.QuaternionRigidBodyPlant`), the true
  disturbances d_i(t), iota_i(t), membership and the state variation (10) at every switch;
* sensors -- :class:`~formation_ftc.components.sensors.tracking_error.TrackingErrorSensors`;
* controller -- :class:`~formation_ftc.components.controllers.force_torque.ForceTorqueController` of
  the translational law (12) and the attitude law (13)
  (:mod:`formation_ftc.components.controllers.yang2013_individual`);
* actuator -- :class:`~formation_ftc.components.actuators.velocity_gain_fault.VelocityGainFaultActuator`:
  the controller fault K2 -> K2f of Sec. 4 on the truth side;
* estimator -- :class:`~formation_ftc.components.estimators.scheduled_diagnosis.ScheduledDiagnosis`:
  the diagnosis (onset + delay) the supervisor sees;
* supervisor -- :class:`~formation_ftc.components.supervisors.switching_supervisor.SwitchingSupervisor`:
  prescribed mode sequence, membership, (29) decisions.

Metrics (every step, inside the run): sup |X| over both limits of every switch, |X| at both limits of
every switch (per spacecraft before it), max |u_i| over the run, the supervisor's decisions.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax.numpy as jnp
import numpy as np

from formation_ftc.components.actuators.velocity_gain_fault import VelocityGainFaultActuator
from formation_ftc.components.controllers.force_torque import ForceTorqueController
from formation_ftc.components.controllers.yang2013_individual import (
    Yang2013AttitudeController,
    Yang2013TranslationalController,
)
from formation_ftc.components.estimators.scheduled_diagnosis import ScheduledDiagnosis
from formation_ftc.components.plants.quaternion_rigid_body import QuaternionRigidBodyPlant
from formation_ftc.components.plants.switched_formation import STATE_DIM, SwitchedFormationPlant
from formation_ftc.components.sensors.tracking_error import TrackingErrorSensors
from formation_ftc.components.supervisors.switching_supervisor import SwitchingSupervisor
from formation_ftc.papers.yang2013.conditions import check
from formation_ftc.papers.yang2013.figures import plot_scenario
from formation_ftc.papers.yang2013.schema import Yang2013Scenario
from formation_ftc.registry import Method, register_method
from formation_ftc.sim.compiled import Compiled, compile_loop
from formation_ftc.sim.components import as_float
from formation_ftc.sim.loop import ClosedLoop
from formation_ftc.sim.metrics import Metric

__all__ = [
    "SwitchedStructure",
    "switched_structure",
    "make_loop",
    "build",
    "input_norm_window",
    "METHOD",
]


@dataclass(frozen=True)
class SwitchedStructure:
    """Slot form of the mode sequence (slot s = spacecraft s + 1).

    ``switch_steps`` (n_modes,) first step of every mode; ``active`` (n_modes, N) bool membership;
    ``P`` (n_modes, N, N) slot maps of the variation matrices S_ij (P[0] = I, unused); ``xstar``
    (n_modes, N, 13) new states X* joining at each switch; ``leaves`` (n_modes, N) bool: member of
    mode j whose state does not continue into mode j + 1; ``x0`` (N, 13) initial error states.
    """

    switch_steps: np.ndarray
    active: np.ndarray
    P: np.ndarray
    xstar: np.ndarray
    leaves: np.ndarray
    x0: np.ndarray
    mode_names: list[str]


def switched_structure(sc: Yang2013Scenario) -> SwitchedStructure:
    """The scenario's mode sequence placed on the N_max spacecraft slots (variation model (10))."""
    n = sc.spacecraft.count
    dt = sc.simulation.dt
    modes = sc.modes
    n_modes = len(modes)
    switch_steps = np.array([round(m.start / dt) for m in modes], dtype=np.int64)
    active = np.zeros((n_modes, n), dtype=bool)
    for j, m in enumerate(modes):
        for s in m.members:
            if s > 0:
                active[j, s - 1] = True
    P = np.zeros((n_modes, n, n))
    P[0] = np.eye(n)
    xstar = np.zeros((n_modes, n, STATE_DIM))
    leaves = np.zeros((n_modes, n), dtype=bool)
    mats = sc.variation_matrices()
    for j in range(1, n_modes):
        m, prev = modes[j], modes[j - 1].members
        S = mats[j - 1]
        for r in range(S.shape[0]):
            if m.members[r] == 0:
                continue
            for c, pc in enumerate(prev):
                if pc > 0:
                    P[j, m.members[r] - 1, pc - 1] = S[
                        r, c
                    ]  # Yang2013 eq. (10): S_ij (x) I_13 on slots
        for ns in m.new_states:
            xstar[j, ns.spacecraft - 1] = ns.vector()
        for c, pc in enumerate(prev):
            if pc > 0 and not np.any(S[:, c]):
                leaves[j - 1, pc - 1] = True
    x0 = np.zeros((n, STATE_DIM))
    for init in sc.initial_state:
        x0[init.spacecraft - 1] = init.vector()
    return SwitchedStructure(switch_steps, active, P, xstar, leaves, x0, [m.name for m in modes])


def _desired_table(sc: Yang2013Scenario) -> tuple:
    """Per mode and slot the three expressions of R~^d(t) [m] ("0" where none is given)."""
    n = sc.spacecraft.count
    table = []
    for m in sc.modes:
        row: list[tuple[str, ...]] = [("0", "0", "0")] * n
        for d in m.desired:
            row[d.spacecraft - 1] = tuple(str(x) for x in d.position)
        table.append(tuple(row))
    return tuple(table)


def input_norm_window(name: str, start: float, end: float, dt: float) -> Metric:
    """Every-step maximum of |u_i| per spacecraft on the half-open window [start, end) [s]."""
    return Metric(
        name,
        "input_norm",
        reduce="max",
        spacecraft="each",
        units="1",
        start=as_float(start),
        end=as_float(end - 0.5 * dt),
    )


def _metrics(sc: Yang2013Scenario, st: SwitchedStructure) -> list[Metric]:
    dt = sc.simulation.dt
    n_steps = sc.simulation.n_steps
    horizon = n_steps * dt
    out = [
        Metric("max_state_norm", "state_norm_peak", reduce="max", units="1"),
        Metric("final_state_norm", "state_norm", reduce="final", units="1"),
        input_norm_window("max_input_norm", 0.0, horizon, dt),
    ]
    starts = [float(k * dt) for k in st.switch_steps]
    for j in range(1, len(starts)):
        if st.switch_steps[j] > n_steps:
            continue
        t = as_float(starts[j])
        out += [
            Metric(f"pre_switch_norm_{j + 1}", "state_norm_left", reduce="at", units="1", start=t),
            Metric(f"post_switch_norm_{j + 1}", "state_norm", reduce="at", units="1", start=t),
            Metric(
                f"pre_switch_sc_norm_{j + 1}",
                "spacecraft_norm_left",
                reduce="at",
                spacecraft="each",
                units="1",
                start=t,
            ),
        ]
    # decision codes (0 none, 1 tolerate by switching, 2 reconfigure); times, modes and (29) margins are
    # recorded signals (the last record holds every decision)
    out.append(
        Metric("supervisor_decision", "supervisor_decision", reduce="final", spacecraft="each")
    )
    return out


def make_loop(sc: Yang2013Scenario, extra_metrics: tuple[Metric, ...] = ()) -> ClosedLoop:
    """The scenario as a composition of components (every number a leaf, every choice static);
    ``extra_metrics`` are appended to the method's metrics (e.g. windows a reproduction compares)."""
    st = switched_structure(sc)
    n = sc.spacecraft.count
    dt = sc.simulation.dt
    c = sc.controller
    mass = as_float(np.full(n, sc.spacecraft.mass))  # truth
    J = as_float(np.diag(sc.spacecraft.inertia))
    # the laws' stated knowledge (controller.nominal_*), never the truth above
    mass_nom = as_float(np.full(n, c.nominal_mass))
    J_nom = as_float(np.diag(c.nominal_inertia))
    attitude = QuaternionRigidBodyPlant(
        inertia=J,
        initial_omega=as_float(st.x0[:, 6:9]),
        initial_quaternion=as_float(st.x0[:, 9:13]),
        disturbance_torque=sc.disturbance.torque,
        gyroscopic=False,
    )
    plant = SwitchedFormationPlant(
        mass=mass,
        attitude=attitude,
        initial_translation=as_float(st.x0[:, 0:6]),
        variation=as_float(st.P),
        new_states=as_float(st.xstar),
        disturbance_force=sc.disturbance.force,
        rotation_coupling=c.rotation_coupling,
    )
    controller = ForceTorqueController(
        force_law=Yang2013TranslationalController(
            count=n, mass=mass_nom, K1=as_float(c.K1), K2=as_float(c.K2)
        ),
        torque_law=Yang2013AttitudeController(
            count=n,
            inertia=J_nom,
            K3=as_float(c.K3),
            K4=as_float(c.K4),
            K5=as_float(c.K5),
            kappa=as_float(c.kappa),
        ),
    )
    # faults on the step grid: times k dt computed as the loop computes t_k (exact comparisons)
    onset = np.full(n, np.inf)
    diagnosis = np.full(n, np.inf)
    delay = np.zeros(n, dtype=np.int64)
    K2f = np.full(n, c.K2)
    for f in sc.faults:
        s = f.spacecraft - 1
        k_f = round(f.onset / dt)
        delay[s] = round(f.diagnosis_delay / dt)
        onset[s] = k_f * dt
        diagnosis[s] = (k_f + delay[s]) * dt
        K2f[s] = f.K2_faulty
    # the faulty law's extra force M_i (K2f - K2) e_V, with the law's mass M_i
    actuator = VelocityGainFaultActuator(
        count=n,
        mass=mass_nom,
        K2=as_float(c.K2),
        K2_faulty=as_float(K2f),
        onset=as_float(onset),
        reconfigurable=sc.supervisor.reconfiguration == "restore_nominal",
    )
    estimator = ScheduledDiagnosis(count=n, diagnosis_time=as_float(diagnosis))
    supervisor = SwitchingSupervisor(
        count=n,
        dt=float(dt),
        switch_steps=jnp.asarray(st.switch_steps),
        active=as_float(st.active),
        leaves_at_next_switch=jnp.asarray(st.leaves),
        eta=as_float(sc.design.eta),
        eta1=as_float(np.full(n, sc.design.eta1)),
        delay_bound_steps=jnp.asarray(delay),
        desired_position=_desired_table(sc),
    )
    sim = sc.simulation
    return ClosedLoop.from_simulation(
        sim,
        plant=plant,
        controller=controller,
        sensors=TrackingErrorSensors(count=n),
        estimator=estimator,
        supervisor=supervisor,
        actuator=actuator,
        metrics=tuple(_metrics(sc, st)) + tuple(extra_metrics),
    )


def build(sc: Yang2013Scenario) -> Compiled:
    """Compile a ``yang2013`` scenario (see module docstring)."""
    return compile_loop(make_loop(sc))


METHOD = register_method(
    Method(
        name="yang2013",
        schema=Yang2013Scenario,
        build=build,
        description="Yang2013 state-varying switched formation (docking, undocking, departure, participation), "
        "error-level closed loop of (12)-(13), dwell-time supervisor and fault tolerance by switching",
        check=check,
        plot=plot_scenario,
    )
)
