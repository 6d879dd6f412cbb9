"""The closed loop: seven component slots, one step, one compiled run (see :mod:`.components`).

:class:`ClosedLoop` is itself a component: its array leaves are every number of the scenario (gains,
masses, fault data, initial states, metric windows, the seed), its static fields the structure (which
components, sizes, step, horizon). :meth:`ClosedLoop.run` is a pure function of the loop, so
``jax.jit(ClosedLoop.run)`` compiles once per :func:`~.components.structure_key` and
``jax.vmap`` batches runs that differ in leaves (:mod:`formation_ftc.sim.batch`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from formation_ftc.core.disturbances import run_key, step_key
from formation_ftc.core.integrators import rk4_autonomous_stages
from formation_ftc.sim import metrics as metric_ops
from formation_ftc.sim.components import (
    KIND_SLOTS,
    Actuator,
    ActuatorInputs,
    CompositionError,
    Controller,
    Estimator,
    FlightInputs,
    IdealActuator,
    Network,
    NetworkInputs,
    NoEstimator,
    NoNetwork,
    NoReference,
    NoSupervisor,
    PerfectSensors,
    Plant,
    Reference,
    SensorInputs,
    Sensors,
    Signal,
    StepContext,
    Supervisor,
    TruthInputs,
    component,
    static,
    structure_key,
    tree_take,
)
from formation_ftc.sim.contract import capability
from formation_ftc.sim.engine import _all_finite, _path_name, run_fixed_step

__all__ = ["ClosedLoop", "LEFT_LIMIT", "COMMAND_SIGNAL", "APPLIED_SIGNAL", "NAVIGATION_ESTIMATE"]

#: fraction of dt subtracted from the last RK stage time for truth-side time signals (faults,
#: disturbances): a fault onset on the step grid acts from the next step on, never inside an RK step
LEFT_LIMIT = 1e-9
COMMAND_SIGNAL = "command"
#: key of an estimate (a mapping) that the controller reads in place of the sensors' measurement: an
#: estimator that detects faults and also navigates (``residual-fdi`` with ``fly_on_filter = true``)
NAVIGATION_ESTIMATE = "navigation"
POSITION_ERROR_SIGNAL = "position_error"
APPLIED_SIGNAL = "applied"
#: key under which :meth:`ClosedLoop.step` hands the stage-integrated metric increments to the run
STAGE_INCREMENTS = "__stage_increments__"
#: most steps whose metric samples are buffered and folded together when the loop chooses
#: (memory: this many samples of the signals the metrics read, per run)
METRIC_BLOCK_MAX = 50
#: the loop folds its metrics a block at a time on its own when it has at least this many step metrics,
#: a block of at least this many steps and a run of at least this many steps (ClosedLoop._metric_block)
METRIC_FOLD_MIN_METRICS = 20
METRIC_FOLD_MIN_BLOCK = 20
METRIC_FOLD_MIN_STEPS = 100_000
#: data folded into the step key for the plant's process noise when the sensors split the key themselves
_PLANT_STREAM = 0x706C616E

PyTree = Any


def _axpy(a, x, y):
    return jax.tree_util.tree_map(lambda xi, yi: yi + a * xi, x, y)


def _once(k, values):
    """``values`` computed once per step: the operand of a conditional whose predicate (``k >= 0``, the
    step index) always holds at run time.

    XLA:CPU fuses cheap element-wise producers into each of their consumers, so a random draw held
    over the step (threefry bits, the normal's inverse-erf polynomial) used to be evaluated again
    inside every RK stage that reads it -- seven to nine copies in a Mehrabian step. A conditional's
    operand cannot be fused into what reads its result, so the draw is evaluated once into a buffer.
    The operations are the same; where the fusion boundaries move, XLA may round differently in the
    last bit (a multiply-add contracted across the old boundary), so results agree to rounding, not
    bit for bit (``benchmarks/held_draws.py`` prints both)."""
    return jax.lax.cond(
        k >= 0, lambda v: v, lambda v: jax.tree_util.tree_map(jnp.zeros_like, v), values
    )


def _held(k, values):
    """:func:`_once` when the step index ``k`` is known, else ``values`` as they are."""
    return values if k is None else _once(k, values)


def _rk4_increment(dt, a, b, c, d):
    """The RK4 increment over a step ``dt`` from the stage slopes (or integrands) ``a .. d``."""
    return (dt / 6.0) * (a + 2.0 * b + 2.0 * c + d)


@component
class ClosedLoop:
    """A scenario compiled into components (every number a leaf, every structural choice static).

    Slots: ``plant`` (truth dynamics), ``reference`` (autonomous reference orbit), ``sensors``,
    ``network``, ``estimator``, ``supervisor``, ``controller``, ``actuator``; ``metrics`` (tuple of
    :class:`~formation_ftc.sim.metrics.Metric`), ``evaluations`` (tuple of
    :class:`~.components.Evaluation`: signals derived from each sample's signals, for records and
    metrics only) and ``seed`` (noise seed, uint32 leaf).
    """

    plant: Plant
    controller: Controller
    reference: Reference = dataclasses.field(default_factory=NoReference)
    sensors: Sensors = dataclasses.field(default_factory=PerfectSensors)
    network: Network = dataclasses.field(default_factory=NoNetwork)
    estimator: Estimator = dataclasses.field(default_factory=NoEstimator)
    supervisor: Supervisor = dataclasses.field(default_factory=NoSupervisor)
    actuator: Actuator = dataclasses.field(default_factory=IdealActuator)
    metrics: tuple = ()
    seed: Any = 0
    #: admissible set of the truth state beyond "finite" (a run leaving it has diverged): largest
    #: relative position [m] and speed [m/s] of any spacecraft (plants that report them)
    max_position: Any = 1.0e6
    max_velocity: Any = 1.0e4
    #: largest body rate [rad/s] and largest |pitch| of an Euler-angle attitude state [rad] (its kinematics
    #: are singular at pi/2): plants that report them
    max_rate: Any = 100.0
    max_pitch: Any = 1.5607963267948966  # pi/2 - 0.01 (SimulationSection's default)
    evaluations: tuple = ()
    dt: float = static(default=0.1)
    n_steps: int = static(default=1)
    record_every: int = static(default=1)
    unroll: int = static(default=1)
    t0: float = static(default=0.0)
    #: steps whose metric samples are folded together (:meth:`_metric_block`): 0 chooses, 1 folds at
    #: every step, L > 1 (a divisor of ``record_every``) buffers L steps' samples and folds them at once
    metric_block: int = static(default=0)

    @classmethod
    def from_simulation(cls, sim: Any, **slots: Any) -> ClosedLoop:
        """A loop of ``slots`` (components, metrics, evaluations) run as a ``[simulation]`` section says:
        step, number of steps (horizon), recording interval, unroll, noise seed and the admissible set
        (``max_position`` [m], ``max_velocity`` [m/s], ``max_rate`` [rad/s], ``max_pitch`` [rad]) --
        set here once for every builder. ``sim`` is a
        :class:`~formation_ftc.config.base.SimulationSection` (or an object with its fields)."""
        return cls(
            **slots,
            seed=np.asarray(sim.seed, dtype=np.uint32),
            dt=float(sim.dt),
            n_steps=int(sim.n_steps),
            record_every=int(sim.record_every),
            unroll=int(sim.unroll),
            max_position=np.float64(sim.max_position),
            max_velocity=np.float64(sim.max_velocity),
            max_rate=np.float64(sim.max_rate),
            max_pitch=np.float64(sim.max_pitch),
        )

    # ------------------------------------------------------------------ validation
    def validate(self, labels: Mapping[str, str] | None = None) -> ClosedLoop:
        """Check that the components fit together (raises :class:`CompositionError` naming both parts);
        returns the loop. Called by :func:`formation_ftc.api.build_loop` before any
        computation (not on pytree reconstruction, where leaves may be placeholders).

        ``labels``: slot (or ``evaluations[j]``) -> the type name the scenario gave it, for the
        messages (default: the component's class name)."""
        for slot, base in KIND_SLOTS.items():
            comp = getattr(self, slot)
            if not isinstance(comp, base):
                raise CompositionError(
                    f"slot '{slot}' needs a {base.__name__}, got {type(comp).__name__}"
                )
        p, c = self.plant, self.controller
        labels = dict(labels or {})
        names = {slot: labels.get(slot, type(comp).__name__) for slot, comp in self._slots()}
        if getattr(c, "quantity", "force") != getattr(p, "quantity", "force"):
            raise CompositionError(
                f"controller {names['controller']} commands {_a(c.quantity)}, but plant "
                f"{names['plant']} is driven by {_a(p.quantity)}: {_a(c.quantity)} law cannot drive "
                "this plant"
            )
        for slot in ("controller", "network", "estimator", "supervisor", "sensors", "actuator"):
            n = getattr(getattr(self, slot), "count", None)
            if n is not None and n != p.count:
                raise CompositionError(
                    f"{slot} {names[slot]} is set up for {n} spacecraft, plant {names['plant']} has "
                    f"{p.count}"
                )
        if self.network.delayed and not getattr(c, "uses_messages", False):
            raise CompositionError(
                f"network {names['network']} delays messages, but controller "
                f"{names['controller']} exchanges none (it has no history to read delayed values from)"
            )
        if self.n_steps % self.record_every:
            raise CompositionError(
                f"record_every = {self.record_every} must divide the number of steps {self.n_steps}"
            )
        if self.metric_block < 0 or (self.metric_block and self.record_every % self.metric_block):
            raise CompositionError(
                f"metric_block = {self.metric_block} must be 0 (automatic) or a divisor of "
                f"record_every = {self.record_every}"
            )
        self._check_needs(names, labels)
        recorded_names = [s.name for s in self.signals()]
        dup = sorted({n for n in recorded_names if recorded_names.count(n) > 1})
        if dup:
            raise CompositionError(
                f"two components record a signal with the same name: {', '.join(dup)}"
            )
        recorded = set(recorded_names)
        for m in self.metrics:
            if m.formula is not None:  # an STL requirement: the signals its atoms read
                from formation_ftc.sim.stl import parse, signals_of

                missing = sorted(signals_of(parse(m.formula)) - recorded)
                if missing:
                    raise CompositionError(
                        f"metric {m.name!r}: the formula reads {', '.join(map(repr, missing))}, "
                        f"not recorded signals of this loop (signals: {', '.join(sorted(recorded))})"
                    )
                continue
            for what, name in (("signal", m.signal), ("gate", m.gate)):
                if name is not None and name not in recorded:
                    raise CompositionError(
                        f"metric {m.name!r}: {what} {name!r} is not a recorded signal of this "
                        f"loop (signals: {', '.join(sorted(recorded))})"
                    )
        return self

    def _slots(self) -> list[tuple[str, Any]]:
        return [(slot, getattr(self, slot)) for slot in KIND_SLOTS]

    def _check_needs(self, names: dict[str, str], labels: dict[str, str]) -> None:
        """Every capability a part needs is provided by some part of the loop (the one place the
        compatibility of components is decided; their ``needs()`` / ``provides()``). A part is named
        by its slot and type (``"controller lqr"``) or, an evaluation, by its label."""
        parts = [(f"{slot} {names[slot]}", c) for slot, c in self._slots()]
        for k, ev in enumerate(self.evaluations):  # a label names the scenario's table or its adder
            key = f"evaluations[{k}]"
            parts.append((labels.get(key, f"{key} {type(ev).__name__}"), ev))
        provided = dict.fromkeys(cap for _, comp in parts for cap in comp.provides())
        for cap in provided:
            capability(cap)  # a declaration naming no capability is a bug
        for label, comp in parts:
            for cap, use in comp.needs().items():
                entry = capability(cap)
                if cap not in provided:
                    raise CompositionError(
                        f"{label} needs {entry.meaning} to {use}, but no part of this loop "
                        f"provides it (provided by: {entry.provided_by})"
                    )

    # ------------------------------------------------------------------ declarations
    def signals(self) -> tuple[Signal, ...]:
        """Every recorded signal of the loop, in slot order (the loop's own signals -- command, applied
        command, position error -- just before the actuator's, the evaluations' last)."""
        q_c, q_p = self.controller.quantity, self.plant.quantity  # commanded, applied quantity
        applied = f"applied {q_p} (after actuator faults)"
        own = [
            Signal(COMMAND_SIGNAL, _dims(q_c), _unit(q_c), f"commanded {q_c}"),
            Signal(APPLIED_SIGNAL, _dims(q_p), _unit(q_p), applied),
        ]
        if self._tracks_position():
            error = "true position minus desired position"
            own.append(Signal(POSITION_ERROR_SIGNAL, ("spacecraft", "axis"), "m", error, "LVLH"))
        before = (sig for slot, c in self._slots() if slot != "actuator" for sig in c.signals())
        evaluated = (sig for ev in self.evaluations for sig in ev.signals())
        return (*before, *own, *self.actuator.signals(), *evaluated)

    @property
    def count(self) -> int:
        return self.plant.count

    def _tracks_position(self) -> bool:
        """True when the plant reports positions and the controller a desired position (evaluation
        only: the flight side never sees the true position)."""
        return (
            type(self.plant).position is not Plant.position
            and type(self.controller).desired_position_at is not Controller.desired_position_at
        )

    # ------------------------------------------------------------------ pieces of one step
    def _time_table(self, t_k, first_only: bool = False, k=None):
        """Time-only signals at t_k, t_k + dt/2, t_k + dt (truth side at the left limit of t_{k+1});
        ``first_only``: at t_k alone (an exact discrete plant, or a caller that reads only t_k). With
        the step index ``k``, the values held over the step are computed once (:func:`_once`)."""
        dt = self.dt
        ts = t_k + dt * jnp.array([0.0] if first_only else [0.0, 0.5, 1.0])
        tf = t_k + dt * jnp.array([0.0] if first_only else [0.0, 0.5, 1.0 - LEFT_LIMIT])

        slots = ("plant", "actuator", "controller", "network", "estimator", "supervisor")
        truth = ("plant", "actuator")
        held_slots = [s for s in slots if getattr(self, s).holds_exogenous]
        live = [s for s in slots if s not in held_slots]  # evaluated at every stage time

        def at(t_flight, t_truth):
            return {
                s: getattr(self, s).exogenous(t_truth if s in truth else t_flight) for s in live
            }

        table = jax.vmap(at)(ts, tf)
        n = ts.shape[0]
        # the first step's table is asked for without its index: k = 0 there
        step = StepContext(jnp.asarray(0 if k is None else k, dtype=jnp.int64), t_k, dt)
        for s in held_slots:  # sampled at t_k, held over the step (zero-order hold)
            table[s] = jax.tree_util.tree_map(
                lambda a: jnp.broadcast_to(a, (n,) + jnp.shape(a)),
                _held(k, getattr(self, s).held_exogenous(step)),
            )
        return table

    def _reference_stages(self, r):
        """Reference state after the step and its values at the four RK stages (or None)."""
        if isinstance(self.reference, NoReference):
            return r, (None, None, None, None)
        r_next, stages = rk4_autonomous_stages(self.reference.rate, r, self.dt)
        # evaluated as one stacked vector: XLA materialises it once instead of fusing scalar cos/sin
        # into every (runs, N, 3) consumer
        vals = self.reference.values(jax.tree_util.tree_map(lambda *a: jnp.stack(a), *stages))
        return r_next, tuple(tree_take(vals, j) for j in range(4))

    def _noise(self, k):
        key = step_key(run_key(self.seed), k)
        if self.sensors.splits_step_key:  # the sensors split the step key into their own streams
            k_sensor, k_plant = key, jax.random.fold_in(key, _PLANT_STREAM)
        else:
            k_sensor, k_plant = jax.random.split(key, 2)
        return _once(k, (self.sensors.noise(k_sensor), self.plant.process_noise(k_plant)))

    def _law_flight(self, y, est, decision, exo, ref, sc):
        """The controller's flight inputs: the sensors' measurement ``y`` and the estimate, or, where
        the estimator is a navigation filter (``navigation = True``), its state estimate in place of the
        measurement (held over the step: the navigation solution at the control rate); an estimate
        with a :data:`NAVIGATION_ESTIMATE` entry (an FDI that also navigates) gives that entry in place
        of the measurement and the whole estimate besides."""
        if self.estimator.navigation:
            return self._flight(est, None, decision, exo, ref, sc)
        if isinstance(est, Mapping) and NAVIGATION_ESTIMATE in est:  # it navigates as well
            return self._flight(est[NAVIGATION_ESTIMATE], est, decision, exo, ref, sc)
        return self._flight(y, est, decision, exo, ref, sc)

    def _flight(self, y, est, decision, exo, ref, sc):
        """Flight inputs with nothing received yet (:meth:`_received` adds the network's messages)."""
        return FlightInputs(y, None, est, decision, exo, ref, sc)

    def _received(self, t, flight, net_state, sc, exo_network):
        """``flight`` with the messages the network delivers at ``t`` (as it is without a network)."""
        if isinstance(self.network, NoNetwork):
            return flight
        msg = self.controller.message(t, flight)
        received = self.network.receive(t, net_state, NetworkInputs(msg, sc, exo_network))
        return flight._replace(received=received)

    def _step_context(self, k) -> StepContext:
        """The context of step ``k`` (its time ``t_k = t0 + k dt``, computed here once)."""
        return StepContext(k, self.t0 + k * self.dt, self.dt)

    def _evaluate(self, t, z, ctx):
        """Derivatives of the integrated state ``z = {plant, controller, usage}`` and the outputs at
        one RK stage; ``ctx`` holds the step's held values and this stage's time signals."""
        exo, ref, s_noise, p_noise, est, dec, net_state, sc, held, act_state = ctx
        x = z["plant"]
        y = self.sensors.measure(t, self.plant.sensed_state(x), SensorInputs(s_noise, ref))
        flight = self._law_flight(y, est, dec, exo["controller"], ref, sc)
        flight = self._received(t, flight, net_state, sc, exo["network"])
        if self.controller.sampled:  # the command held over the step, no state derivative
            (u, ctl_out), dc = held, None
        else:
            u, dc, ctl_out = self.controller.output(t, z["controller"], flight)
        act_in = ActuatorInputs(exo["actuator"], act_state, dec, x)
        applied = self.actuator.apply(t, u, act_in)
        truth = TruthInputs(applied, exo["plant"], ref, p_noise, dec)
        dx = self.plant.derivative(t, x, truth)
        deriv = {"plant": dx, "controller": dc, "usage": self.plant.usage_rates(t, x, u)}
        outputs = dict(self.plant.outputs(t, x, truth))
        outputs.update(self.actuator.outputs(t, u, act_in))
        if self._tracks_position():  # true minus desired position
            r, r_d = self.plant.position(x), self.controller.desired_position_at(exo["controller"])
            outputs[POSITION_ERROR_SIGNAL] = r - r_d
        outputs.update(ctl_out)
        outputs[COMMAND_SIGNAL] = u
        outputs[APPLIED_SIGNAL] = applied
        return deriv, outputs

    def _start(self, sc: StepContext, state: dict, exo0, ref0, s_noise):
        """Steps (1)-(5) at t_k, shared by :meth:`step` and :meth:`observe`: the measurement, the
        estimator and supervisor updates, the message of t_k pushed into the network history and the
        sampled controller's command (held over the step)."""
        y = self.sensors.measure(
            sc.t, self.plant.sensed_state(state["plant"]), SensorInputs(s_noise, ref0)
        )
        # (3)-(4) the estimator and supervisor updates
        est_state, est = self.estimator.update(
            sc.t, state["estimator"], self._flight(y, None, None, exo0["estimator"], ref0, sc)
        )
        sup_state, dec = self.supervisor.update(
            sc.t, state["supervisor"], self._flight(y, est, None, exo0["supervisor"], ref0, sc)
        )
        est = _once(sc.k, est)  # an estimate (a noisy FDI report, ...) is held over the step
        net_state = state["network"]
        if not isinstance(self.network, NoNetwork):
            # (2) the message of t_k joins the history before anyone reads it (newest sample = t_k)
            msg_k = self.controller.message(
                sc.t, self._law_flight(y, est, dec, exo0["controller"], ref0, sc)
            )
            net_state = self.network.push(net_state, msg_k)
        held, ctl_next = None, state["controller"]
        if self.controller.sampled:
            flight = self._law_flight(y, est, dec, exo0["controller"], ref0, sc)
            flight = self._received(sc.t, flight, net_state, sc, exo0["network"])
            u, ctl_next, ctl_out = self.controller.output(sc.t, state["controller"], flight)
            held = (u, ctl_out)
        return y, est_state, est, sup_state, dec, net_state, held, ctl_next

    def initial_state(self) -> dict:
        """State at t0 (the loop's every-step metric accumulators start from the t0 signals)."""
        x0 = self.plant.initial_state()
        r0 = self.reference.initial_state()
        ref0 = None if isinstance(self.reference, NoReference) else self.reference.values(r0)
        t0 = jnp.asarray(self.t0, dtype=jnp.float64)
        s_noise, _ = self._noise(jnp.asarray(0, dtype=jnp.int64))
        y0 = self.sensors.measure(t0, self.plant.sensed_state(x0), SensorInputs(s_noise, ref0))
        state = dict(
            plant=x0,
            reference=r0,
            controller=self.controller.initial_state(),
            estimator=self.estimator.initial_state(y0),
            supervisor=self.supervisor.initial_state(),
            actuator=self.actuator.initial_state(),
            usage={name: jnp.zeros(self.plant.usage_shape()) for name in self.plant.usage_names()},
        )
        state["network"] = None
        if not isinstance(self.network, NoNetwork):
            exo0 = tree_take(self._time_table(t0, first_only=True), 0)
            sc0 = self._step_context(jnp.asarray(0, dtype=jnp.int64))
            msg0 = self.controller.message(
                t0, self._flight(y0, None, None, exo0["controller"], ref0, sc0)
            )
            state["network"] = self.network.initial_state(msg0)
        return state

    def step(self, k, state: dict) -> tuple[dict, dict]:
        """One control step k -> k + 1; returns the new state and the signals at t_k."""
        dt = self.dt
        sc = self._step_context(k)
        t_k = sc.t
        exact = self.plant.integration == "exact"  # one stage: time signals at t_k only
        table = self._time_table(t_k, first_only=exact, k=k)
        exos = [tree_take(table, j) for j in ((0, 0, 0, 0) if exact else (0, 1, 1, 2))]
        r_next, refs = self._reference_stages(state["reference"])
        s_noise, p_noise = self._noise(k)
        x = state["plant"]
        y, est_state, est, sup_state, dec, net_state, held, ctl_next = self._start(
            sc, state, exos[0], refs[0], s_noise
        )

        # a stage-integrated metric may read an evaluation's signal (e.g. the applied force per unit
        # mass): the evaluations see each stage's outputs and the step's held FDI / supervisor signals
        # (computed once per step, and only when such a metric exists)
        held_signals = None
        if self._stage_reads_evaluations():
            held_signals = self._held_outputs(t_k, est_state, est, sup_state, dec)

        def stage_signals(o: dict) -> dict:
            return o if held_signals is None else self._evaluated({**o, **held_signals})

        held_over_step = (s_noise, p_noise, est, dec, net_state, sc, held, state["actuator"])

        def ctx(j):
            return (exos[j], refs[j], *held_over_step)

        # the state integrated over the step (a sampled controller's is not: it is held)
        ctl = None if self.controller.sampled else state["controller"]
        z = {"plant": x, "controller": ctl, "usage": state["usage"]}
        if exact:
            deriv, outputs = self._evaluate(t_k, z, ctx(0))
            truth = TruthInputs(outputs[APPLIED_SIGNAL], exos[0]["plant"], refs[0], p_noise, dec)
            x_next = self.plant.exact_step(t_k, x, truth, dt)
            z_next = dict(
                plant=x_next, controller=None, usage=_axpy(dt, deriv["usage"], z["usage"])
            )
            if self._stage_metrics():  # rectangle rule over the step
                outputs[STAGE_INCREMENTS] = tuple(
                    None if v is None else dt * v
                    for v in metric_ops.stage_values(self._streamed, stage_signals(outputs))
                )
        else:
            k1, outputs = self._evaluate(t_k, z, ctx(0))
            k2, o2 = self._evaluate(t_k + 0.5 * dt, _axpy(0.5 * dt, k1, z), ctx(1))
            k3, o3 = self._evaluate(t_k + 0.5 * dt, _axpy(0.5 * dt, k2, z), ctx(2))
            k4, o4 = self._evaluate(t_k + dt, _axpy(dt, k3, z), ctx(3))
            z_next = jax.tree_util.tree_map(
                lambda xi, *slopes: xi + _rk4_increment(dt, *slopes), z, k1, k2, k3, k4
            )
            # integrals of stage-integrated metrics over the step (RK4 weights)
            if self._stage_metrics():
                values = [
                    metric_ops.stage_values(self._streamed, stage_signals(o))
                    for o in (outputs, o2, o3, o4)
                ]
                outputs[STAGE_INCREMENTS] = tuple(
                    None if a is None else _rk4_increment(dt, a, b, c, d)
                    for a, b, c, d in zip(*values, strict=True)
                )
        act_in = ActuatorInputs(exos[0]["actuator"], state["actuator"], dec, x)
        act_state = self.actuator.update(t_k, state["actuator"], outputs[COMMAND_SIGNAL], act_in)
        # discrete change of the truth state at t_{k+1} commanded by the decision in force (default none)
        z_next = dict(z_next, plant=self.plant.jump(t_k + dt, z_next["plant"], dec))
        outputs.update(self._held_outputs(t_k, est_state, est, sup_state, dec))
        # (7) the estimator's time update over [t_k, t_k + dt] with the command held over the step
        est_state = self.estimator.predict(t_k, est_state, outputs[COMMAND_SIGNAL], dt)
        # the state at t_{k+1}: the integrated parts (plant, continuous controller, usage) and the rest
        new = dict(z_next, reference=r_next, estimator=est_state, supervisor=sup_state)
        new.update(actuator=act_state, network=net_state)
        if self.controller.sampled:  # its next state from the update at t_k
            new["controller"] = ctl_next
        return new, outputs

    def _held_outputs(self, t_k, est_state, est, sup_state, dec) -> dict:
        """The estimator's and the supervisor's signals at t_k (held over the step)."""
        est_out = self.estimator.outputs(t_k, est_state, est)
        return {**est_out, **self.supervisor.outputs(t_k, sup_state, dec)}

    def _stage_reads_evaluations(self) -> bool:
        """True when a stage-integrated metric reads a signal of an evaluation."""
        names = {sig.name for ev in self.evaluations for sig in ev.signals()}
        return any(
            m.reduce in metric_ops.STAGE_REDUCTIONS and m.signal in names for m in self._streamed
        )

    def _stage_metrics(self) -> bool:
        """True when a metric is integrated at the integrator's stages (:data:`~.metrics.STAGE_REDUCTIONS`)."""
        return any(m.reduce in metric_ops.STAGE_REDUCTIONS for m in self._streamed)

    def observe(self, k, state: dict) -> dict:
        """Signals at t_k from the state at t_k: what :meth:`step` computes from t_k -- the same
        :meth:`_start` (estimator and supervisor updates at t_k, the sampled command) and the same first
        stage -- without the rest of the step, so a record is what the step used."""
        sc = self._step_context(k)
        exo = tree_take(self._time_table(sc.t, first_only=True, k=k), 0)
        r = state["reference"]
        ref = None if isinstance(self.reference, NoReference) else self.reference.values(r)
        s_noise, p_noise = self._noise(k)
        _, est_state, est, sup_state, dec, net_state, held, _ = self._start(
            sc, state, exo, ref, s_noise
        )
        z = {"plant": state["plant"], "controller": state["controller"], "usage": state["usage"]}
        ctx = (exo, ref, s_noise, p_noise, est, dec, net_state, sc, held, state["actuator"])
        _, outputs = self._evaluate(sc.t, z, ctx)
        outputs.update(self._held_outputs(sc.t, est_state, est, sup_state, dec))
        return self._sample(state, outputs)

    def _sample(self, state: dict, outputs: dict) -> dict:
        """The step's ``outputs`` at t_k with the usage integrals at t_k and every evaluation's signals."""
        outputs.update(state["usage"])
        return self._evaluated(outputs)

    def _evaluated(self, outputs: dict) -> dict:
        """``outputs`` with every evaluation's signals added."""
        for ev in self.evaluations:
            outputs.update(ev.outputs(outputs))
        return outputs

    # ------------------------------------------------------------------ the run
    def prepared(self) -> ClosedLoop:
        """The loop with the plant's per-run precomputation done (:meth:`~.components.Plant.prepare`,
        e.g. an exact discretisation from the parameter leaves); called once per run, outside the
        time loop."""
        plant = self.plant.prepare(self.dt)
        return self if plant is self.plant else dataclasses.replace(self, plant=plant)

    def run(self) -> dict:
        """Pure, jittable, vmappable: records, final state, divergence step and metric values."""
        return self.prepared()._run()

    def _run(self) -> dict:
        state0 = self.initial_state()
        # the accumulators' shapes come from the signals' shapes (traced, not computed: the records'
        # single ``observe`` in the loop computes the signals at t0)
        shapes = jax.eval_shape(self.observe, jnp.asarray(0, dtype=jnp.int64), state0)
        acc0 = metric_ops.init_accumulators(
            self._streamed, jax.tree_util.tree_map(lambda s: jnp.zeros(s.shape, s.dtype), shapes)
        )

        metric_block = self._metric_block()
        folding = metric_block > 1

        def step(k, carry):
            state, acc = carry
            new, outputs = self.step(k, state)
            stage_inc = outputs.pop(STAGE_INCREMENTS, None)
            if stage_inc is not None:
                acc = metric_ops.update_stage_accumulators(
                    self._streamed, acc, self.t0 + k * self.dt, self.dt, stage_inc
                )
            outputs = self._sample(state, outputs)
            # the sample goes to fold(): the metrics of a block of steps are folded at once
            if folding:
                return (new, acc), metric_ops.pack_sample(self._streamed, outputs)
            acc = metric_ops.update_accumulators(
                self._streamed, acc, self.t0 + k * self.dt, self.dt, outputs
            )
            return new, acc

        def fold(k, carry, samples):
            samples = metric_ops.unpack_samples(self._streamed, shapes, samples)
            return carry[0], metric_ops.fold_block(
                self._streamed, carry[1], k, self.t0, self.dt, samples
            )

        out = run_fixed_step(
            step,
            lambda k, carry: self.observe(k, carry[0]),
            (state0, acc0),
            self.n_steps,
            self.record_every,
            self.unroll,
            check_of=lambda c: (c[0]["plant"], c[0]["controller"], c[0]["estimator"]),
            admissible=self.admissible,
            fold=fold if folding else None,
            fold_every=metric_block,
        )
        state_n, acc = out["final"]
        # the horizon sample is the last record (the signals of the final state at t_n); a run that left
        # its admissible set never reached the horizon: its metrics stay those accumulated up to the
        # start of the failing record block (the returned snapshot), with no horizon sample
        sig_n = jax.tree_util.tree_map(lambda r: r[-1], out["records"])
        acc_n = metric_ops.update_accumulators(
            self._streamed, acc, self.t0 + self.n_steps * self.dt, self.dt, sig_n, is_final=True
        )
        reached = out["diverged_step"] < 0
        acc = jax.tree_util.tree_map(lambda a_n, a: jnp.where(reached, a_n, a), acc_n, acc)
        metrics = self._with_requirements(metric_ops.finalize(self._streamed, acc), out)
        # records, diverged_step and last_finite (the carry, accumulators included) as they are
        return dict(out, final=state_n, metrics=metrics)

    @property
    def _streamed(self) -> tuple:
        """The metrics folded step by step (every metric but the STL requirements)."""
        return tuple(m for m in self.metrics if m.formula is None)

    def _with_requirements(self, streamed: Any, out: dict) -> tuple:
        """The values of every metric in order: the folded ones, and the robustness of each STL
        requirement (:mod:`formation_ftc.sim.stl`) on the run's records, computed here, inside the
        compiled run (a campaign keeps the number, not the records). A run that diverged has NaN
        records after its failure, hence a NaN robustness: it does not pass."""
        from formation_ftc.sim.stl import parse, robustness

        folded = iter(streamed)
        step = self.dt * self.record_every
        return tuple(
            next(folded)
            if m.formula is None
            else robustness(parse(m.formula), out["records"], step)
            for m in self.metrics
        )

    def _metric_block(self) -> int:
        """Steps whose metric samples are folded together (:func:`~.metrics.fold_block`).

        ``metric_block`` when set; otherwise (0) blocks of the largest divisor of ``record_every`` up to
        :data:`METRIC_BLOCK_MAX` for a long run with many step metrics -- at least
        :data:`METRIC_FOLD_MIN_METRICS` metrics, a block of at least :data:`METRIC_FOLD_MIN_BLOCK`
        steps and :data:`METRIC_FOLD_MIN_STEPS` steps -- and 1 (every step) else. Folding takes the
        metrics' small kernels out of every step, but its vectorised reductions make the program larger
        (longer to compile) and, under ``vmap``, where a step's kernels already serve the whole batch,
        cost more than they save; ``benchmarks/metric_fold.py`` measures both."""
        if not metric_ops.block_signals(self._streamed):
            return 1
        if self.metric_block:
            return self.metric_block
        every = self.record_every
        block = max(d for d in range(1, min(every, METRIC_BLOCK_MAX) + 1) if every % d == 0)
        many = sum(metric_ops.reads_steps(m) for m in self._streamed)
        long_run = self.n_steps >= METRIC_FOLD_MIN_STEPS and block >= METRIC_FOLD_MIN_BLOCK
        return block if long_run and many >= METRIC_FOLD_MIN_METRICS else 1

    def _bounded(self, x) -> list[tuple[str, Any, Any]]:
        """(name, magnitude per spacecraft, bound) of the bounded truth quantities of plant state x."""
        out = []
        vectors = (
            ("position", self.max_position),
            ("velocity", self.max_velocity),
            ("angular_rate", self.max_rate),
        )
        for name, bound in vectors:  # Euclidean norm per spacecraft
            v = getattr(self.plant, name)(x) if hasattr(self.plant, name) else None
            if v is not None:
                out.append((f"plant.{name}", jnp.sqrt(jnp.sum(v * v, axis=-1)), bound))
        pitch = self.plant.euler_pitch(x) if hasattr(self.plant, "euler_pitch") else None
        if pitch is not None:
            out.append(("plant.pitch", jnp.abs(pitch), self.max_pitch))
        return out

    def admissible(self, carry) -> jax.Array:
        """True while the checked state (plant, controller, estimator) is finite and every bounded
        truth quantity is within its bound."""
        c = carry[0]
        ok = _all_finite((c["plant"], c["controller"], c["estimator"]))
        for _, mag, bound in self._bounded(carry[0]["plant"]):
            ok = jnp.logical_and(ok, jnp.all(jnp.logical_not(mag > bound)))
        return ok

    #: carry paths the admissible set checks (for naming the variable that left it)
    admissible.checked_prefixes = ("0.plant", "0.controller", "0.estimator")  # type: ignore[attr-defined]

    def violations(self, carry) -> list[tuple[str, tuple[int, ...], int | None]]:
        """(variable, index, spacecraft) of every bounded quantity outside its bound (numpy side)."""
        return [
            (
                f"{name} (|.| > {float(np.asarray(bound)):g})",
                tuple(map(int, idx)),
                int(idx[0]) if len(idx) else None,
            )
            for name, mag, bound in self._bounded(carry[0]["plant"])
            for idx in np.argwhere(np.asarray(mag) > np.asarray(bound))
        ]

    # ------------------------------------------------------------------ results (numpy side)
    @property
    def static_key(self) -> Any:
        """Compile key: two loops with equal keys share one compiled program and can be batched
        (:func:`~.components.structure_key`: tree definition, static fields, leaf shapes and dtypes)."""
        return structure_key(self)

    def dataset(self, out: Mapping[str, Any], n_records: int, attrs: dict | None = None) -> Any:
        """``xarray.Dataset`` of the first ``n_records`` records of a run's output ``out``: every
        declared signal with its dims, units, long_name and frame; time [s] from ``t0``."""
        from formation_ftc.sim.records import records_to_dataset

        return records_to_dataset(self, out["records"], n_records, attrs)

    def metric_values(self, out: Mapping[str, Any]) -> dict[str, float]:
        """``{name: value}`` of the metrics a run folded (``out["metrics"]``), per spacecraft where a
        metric is (``name[k]``)."""
        return metric_ops.metrics_dict(self.metrics, out["metrics"])

    def spacecraft_axis(self, name: str) -> int | None:
        """Axis of the spacecraft dimension of the carry leaf ``name`` (as diagnostics print it:
        ``"0.plant.q"``), or None (no such leaf, or one not per spacecraft)."""
        state = jax.eval_shape(lambda p: (p.initial_state(), None), self)
        flat, _ = jax.tree_util.tree_flatten_with_path(state)
        leaf = next((leaf for path, leaf in flat if _path_name(path) == name), None)
        if leaf is None:
            return None
        shape, n = np.shape(leaf), self.count
        if "values" in name.split(".") and len(shape) >= 2 and shape[1] == n:  # history rings
            return 1
        return 0 if len(shape) >= 1 and shape[0] == n else None

    def replay_step(self):
        """``step(k, carry)`` over the run's carry (for divergence diagnostics)."""
        loop = self.prepared()
        return lambda k, carry: (loop.step(k, carry[0])[0], carry[1])  # (new state, accumulators)


def _dims(quantity: str) -> tuple[str, str]:
    """Dimensions of a command: per spacecraft, a vector of ``axis`` (x, y, z), or of
    ``wrench_component`` for a force-torque wrench [f; tau] (6 components)."""
    return ("spacecraft", "wrench_component" if quantity == "wrench" else "axis")


def _unit(quantity: str) -> str:
    return {"force": "N", "torque": "N m", "acceleration": "m s-2"}.get(quantity, "1")


def _a(word: str) -> str:
    """``word`` with its indefinite article ("a force", "an acceleration")."""
    return f"{'an' if word[:1] in 'aeiou' else 'a'} {word}"
