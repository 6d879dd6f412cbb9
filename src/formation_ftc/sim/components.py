"""The component contract: plant, sensors, network, estimator, supervisor, controller, actuator.

Every closed loop in formation-ftc is a :class:`ClosedLoop` that fills seven slots with components.
A component is an immutable pytree (a frozen dataclass registered with
``jax.tree_util.register_dataclass``): its **structure** -- sizes, which law, which fault model,
expression texts, static flags -- is declared with :func:`static` fields, and its **numbers** are
array leaves. The component *is* its parameters: a Monte Carlo campaign varies the leaves and
``jax.vmap`` batches them, while the tree definition (which includes every static field) is the
compile key (:func:`structure_key`). Nobody writes a compile key by hand.

Why frozen dataclasses and not Equinox: the split we need (``static`` metadata vs array leaves,
hashable treedef) is exactly what ``jax.tree_util.register_dataclass`` provides; it adds no dependency
and no metaclass, and a component is an ordinary dataclass that ``dataclasses.replace`` updates.

Truth side and flight side are separate types. The plant and the actuator receive
:class:`TruthInputs` / :class:`ActuatorInputs` (true state, true faults, true disturbance); the
estimator, supervisor and controller receive :class:`FlightInputs`, which has no field for the true
state, the true fault or the true disturbance -- only measurements, received messages, estimates, the
supervisor's decision and the flight side's own time-only signals.

One control step (k -> k+1, ``t_k = t0 + k dt``; the order every method follows)::

    (0) time-only signals of every component at t_k, t_k + dt/2, t_k + dt (one batched evaluation;
        truth-side signals at the left limit t_{k+1}^- so a fault onset on the grid never falls inside
        a step); the reference orbit's RK4 stage values (autonomous, computed once per step)
    (1) sensors: noise drawn for the step (held), y_k = measure(x_k)
    (2) network: messages of every spacecraft, read with their delays from the history
    (3) estimator / FDI update (discrete, once per step)
    (4) supervisor update (discrete decisions: modes, flags, reconfiguration)
    (5) controller: sampled -> u_k once and held; continuous -> evaluated at every RK stage with its
        adaptive states integrated together with the plant
    (6) actuator: faults, saturation (truth side)
    (7) plant: RK4 over [t_k, t_k + dt] (or the plant's exact discrete step)
    (8) network history push, every-step metric accumulators, records every ``record_every`` steps

Every kind has one signature shape: ``method(self, t, state, inputs) -> ...`` with ``self`` the
numeric parameters. Every component declares the signals it records (:class:`Signal`: name, dims, SI
units, long_name, frame); :func:`formation_ftc.sim.results.to_dataset` turns records into an
``xarray.Dataset`` generically and :class:`formation_ftc.sim.metrics.Metric` accumulates metrics at
every step inside the compiled run.
"""

from __future__ import annotations

import dataclasses
from typing import Any, ClassVar, NamedTuple, TypeVar, dataclass_transform

import jax
import jax.numpy as jnp
import numpy as np  # noqa: F401 - the doctests' np

from formation_ftc import _lazy_jax

# JAX-free names that catalog sections use while validating (re-exported here)
from formation_ftc.sim.contract import CompositionError
from formation_ftc.sim.contract import as_float as as_float

__all__ = [
    "component",
    "static",
    "structure_key",
    "Signal",
    "TruthInputs",
    "ActuatorInputs",
    "SensorInputs",
    "FlightInputs",
    "StepContext",
    "NetworkInputs",
    "Plant",
    "Reference",
    "Sensors",
    "Network",
    "Estimator",
    "Supervisor",
    "Controller",
    "Actuator",
    "NoReference",
    "PerfectSensors",
    "NoNetwork",
    "NoEstimator",
    "NoSupervisor",
    "IdealActuator",
    "Evaluation",
    "CompositionError",
    "KIND_SLOTS",
]

PyTree = Any
T = TypeVar("T")


# --------------------------------------------------------------------------------------------------
# Declaring components
# --------------------------------------------------------------------------------------------------
def static(default: Any = dataclasses.MISSING, **kwargs: Any) -> Any:
    """A structural (static) field: part of the compile key, never batched; must be hashable.

    Pass the default by keyword (``static(default=1)``): type checkers read field specifiers per
    PEP 681 and only recognise a keyword ``default`` (a positional one is accepted at run time).

    Parameters
    ----------
    default : Any, optional
        Default value (hashable).
    **kwargs
        Further :func:`dataclasses.field` arguments (``metadata`` is merged).

    Returns
    -------
    dataclasses.Field
        A field whose metadata marks it static.

    Examples
    --------
    >>> import jax
    >>> import numpy as np
    >>> from formation_ftc.sim.components import component, static
    >>> @component
    ... class Gain:
    ...     k: object                       # a leaf [1/s]
    ...     count: int = static(default=1)  # structure
    >>> jax.tree_util.tree_leaves(Gain(k=np.array([0.5, 0.7]), count=2))
    [array([0.5, 0.7])]
    """
    metadata = dict(kwargs.pop("metadata", {}) or {}, static=True)
    return dataclasses.field(default=default, metadata=metadata, **kwargs)


@dataclass_transform(frozen_default=True, field_specifiers=(dataclasses.field, static))
def component(cls: type[T]) -> type[T]:
    """Make ``cls`` a frozen dataclass registered as a JAX pytree.

    Fields declared with :func:`static` are metadata of the tree definition (compile key); every other
    field is a child (an array leaf or a nested component). Subclasses must be decorated again.

    Parameters
    ----------
    cls : type
        The class to decorate.

    Returns
    -------
    type
        ``cls`` as a frozen dataclass registered with ``jax.tree_util.register_dataclass``.

    Examples
    --------
    >>> import dataclasses
    >>> import jax
    >>> import numpy as np
    >>> from formation_ftc.sim.components import component, static
    >>> @component
    ... class Damper:
    ...     c: object                       # damping [N s/m]
    ...     count: int = static(default=1)
    >>> d = Damper(c=np.array([2.0]))
    >>> jax.tree_util.tree_map(lambda x: 3.0 * x, d)
    Damper(c=array([6.]), count=1)
    >>> dataclasses.replace(d, count=2).count
    2
    """
    cls = dataclasses.dataclass(frozen=True, eq=False)(cls)
    fields = dataclasses.fields(cls)  # type: ignore[arg-type]  # cls is a dataclass from the line above
    meta = [f.name for f in fields if f.metadata.get("static", False)]
    data = [f.name for f in fields if not f.metadata.get("static", False)]
    for f in fields:
        if f.name in meta and f.default is not dataclasses.MISSING:
            try:
                hash(f.default)
            except TypeError as exc:  # pragma: no cover - a declaration error caught at import
                raise TypeError(f"{cls.__name__}.{f.name}: static fields must be hashable") from exc
    # at once, or when a lazy ``jax`` proxy imports JAX (:mod:`formation_ftc._lazy_jax`: ``check``)
    _lazy_jax.call_when_imported(
        lambda jax: jax.tree_util.register_dataclass(cls, data_fields=data, meta_fields=meta)
    )
    return cls


def structure_key(tree: PyTree) -> Any:
    """Compile key of a component tree: its tree definition (static fields included) and the shapes
    and dtypes of its leaves. Two trees with equal keys run with one compiled program.

    Parameters
    ----------
    tree : pytree
        A component (or any pytree).

    Returns
    -------
    tuple
        ``(treedef, ((shape, dtype name), ...))``, hashable.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.sim.components import component, static, structure_key
    >>> @component
    ... class Gain:
    ...     k: object
    ...     count: int = static(default=1)
    >>> structure_key(Gain(k=np.array([0.5]))) == structure_key(Gain(k=np.array([9.0])))  # numbers differ
    True
    >>> structure_key(Gain(k=np.array([0.5]))) == structure_key(Gain(k=np.array([0.5]), count=2))
    False
    >>> structure_key(Gain(k=np.array([0.5])))[1]
    (((1,), 'float64'),)
    """
    leaves, treedef = jax.tree_util.tree_flatten(tree)
    return treedef, tuple((jnp.shape(x), jnp.result_type(x).name) for x in leaves)


class Signal(NamedTuple):
    """One recorded signal: ``dims`` exclude the time dimension; units are UDUNITS strings."""

    name: str
    dims: tuple[str, ...]
    units: str
    long_name: str
    frame: str | None = None


# --------------------------------------------------------------------------------------------------
# Inputs of each kind: the truth / flight boundary is a type boundary
# --------------------------------------------------------------------------------------------------
class TruthInputs(NamedTuple):
    """What the truth plant's dynamics may use at one RK stage."""

    force: jax.Array  # applied actuator output (after faults and saturation), SI
    exogenous: PyTree  # the plant's own time-only signals (true disturbance, ...)
    reference: PyTree  # reference-orbit values at this stage (None without a reference)
    process_noise: PyTree  # per-step process noise (held over the step)
    #: the supervisor's decision in force over the step, as the truth side executes it (membership of a
    #: switched formation, ...); None without a supervisor
    decision: PyTree = None


class ActuatorInputs(NamedTuple):
    """What the actuator chain may use: its own time-only signals (true faults) and its state; the
    supervisor's decision in force (e.g. a switch to a redundant unit) and the true plant state (for a
    fault whose effect depends on the state); both None where the loop has none."""

    exogenous: PyTree
    state: PyTree
    decision: PyTree = None
    plant_state: PyTree = None


class SensorInputs(NamedTuple):
    """Measurement noise drawn for the step and the reference-orbit values."""

    noise: PyTree
    reference: PyTree


class StepContext(NamedTuple):
    """The control step in progress, given to the flight side with its inputs: step index ``k``
    (int64), its time ``t = t0 + k dt`` [s] and the control step ``dt`` [s]. A component that counts
    steps reads ``k`` here instead of recovering it from a time."""

    k: jax.Array
    t: jax.Array
    dt: float


class NetworkInputs(NamedTuple):
    """Messages sent now, the control step in progress (its index, start time ``step.t`` [s] and
    ``step.dt`` [s]: a network that keeps a history samples it at the loop's step, never its own) and
    the network's time-only signals."""

    messages: PyTree
    step: StepContext
    exogenous: PyTree


class FlightInputs(NamedTuple):
    """Everything the flight side (estimator, supervisor, controller) may see. There is deliberately
    no field for the true state, the true fault or the true disturbance."""

    measurement: PyTree  # sensors' output (noisy, possibly relative)
    received: PyTree  # what the network delivered (None without a network)
    estimate: PyTree  # the estimator's output (None without an estimator)
    decision: PyTree  # the supervisor's output (None without a supervisor)
    exogenous: PyTree  # the receiving component's own time-only signals (desired trajectory, ...)
    reference: PyTree  # reference-orbit values known on board (None without a reference)
    step: StepContext  # the control step in progress (index, time, dt)


# --------------------------------------------------------------------------------------------------
# The seven kinds (plus the reference orbit). Default methods are the "nothing there" behaviour.
# --------------------------------------------------------------------------------------------------
class _Kind:
    kind: ClassVar[str] = ""

    def signals(self) -> tuple[Signal, ...]:
        """Signals this component records (declared once)."""
        return ()

    def exogenous(self, t: jax.Array) -> PyTree:
        """Time-only signals [SI] at time ``t``; evaluated once per step for the three RK stage times."""
        return None

    def coords(self) -> dict[str, Any]:
        """Coordinate values of the dimensions this component's signals introduce (e.g. channel names)."""
        return {}

    def provides(self) -> frozenset[str]:
        """What this part gives the other parts of the loop: names of
        :data:`~formation_ftc.sim.contract.CAPABILITIES`."""
        return frozenset()

    def needs(self) -> dict[str, str]:
        """What this part needs another part of the loop to provide: capability name (of
        :data:`~formation_ftc.sim.contract.CAPABILITIES`) -> what it uses it for (a verb phrase,
        e.g. ``"design its gain on the reference orbit"``). Checked by
        :meth:`~formation_ftc.sim.loop.ClosedLoop.validate`."""
        return {}

    #: True: the time signals are sampled at the step start t_k and held over the step (zero-order
    #: hold, e.g. a fault profile or a disturbance sequence applied through a sample-and-hold); the loop
    #: evaluates :meth:`held_exogenous` once per step
    holds_exogenous: ClassVar[bool] = False

    def held_exogenous(self, step: StepContext) -> PyTree:
        """The time-only signals held over the control step ``step`` (parts with ``holds_exogenous``):
        :meth:`exogenous` at its start ``step.t``; a part that draws a value per step reads the step
        index ``step.k`` (the loop's), never recovers it from a time."""
        return self.exogenous(step.t)


class Plant(_Kind):
    """Truth dynamics of every spacecraft. Owns the true disturbances (:meth:`exogenous`) and the
    process noise. ``quantity`` names what the actuator must deliver (``"force"`` [N] or
    ``"torque"`` [N m]); ``count`` is the number of spacecraft."""

    kind: ClassVar[str] = "plant"
    quantity: ClassVar[str] = "force"
    #: "rk4": continuous dynamics; "exact": the plant provides an exact discrete step (LTI, ZOH)
    integration: ClassVar[str] = "rk4"

    @property
    def count(self) -> int:  # pragma: no cover - every plant overrides
        raise NotImplementedError

    def provides(self) -> frozenset[str]:
        """What every plant gives the loop by its own declarations: ``applied-forces`` when it is
        driven by a force, ``recorded-positions`` when it records ``position``, ``true-masses`` when it
        has a ``mass`` field. A plant that provides more adds to ``super().provides()``."""
        caps = {"applied-forces"} if self.quantity == "force" else set()
        if any(s.name == "position" for s in self.signals()):
            caps.add("recorded-positions")
        if getattr(self, "mass", None) is not None:
            caps.add("true-masses")
        return frozenset(caps)

    def initial_state(self) -> PyTree:  # pragma: no cover
        raise NotImplementedError

    def derivative(
        self, t: jax.Array, x: PyTree, inputs: TruthInputs
    ) -> PyTree:  # pragma: no cover
        raise NotImplementedError

    def exact_step(self, t: jax.Array, x: PyTree, inputs: TruthInputs, dt: float) -> PyTree:
        raise CompositionError(f"plant {type(self).__name__} has no exact discrete step")

    def prepare(self, dt: float) -> Plant:
        """The plant with its per-run precomputation done from its leaves (e.g. the exact
        discretisation over the step ``dt`` [s] of an LTI plant); the loop calls it once per run,
        outside the time loop. Default: nothing to precompute."""
        return self

    def process_noise(self, key: jax.Array) -> PyTree:
        return None

    def jump(self, t: jax.Array, x: PyTree, decision: PyTree) -> PyTree:
        """The state after a discrete change at the end of a step (``t = t_{k+1}``), given the
        supervisor's decision in force over the step (e.g. the state variation of a switched formation
        when spacecraft dock, undock, depart or join). Default: no jump."""
        return x

    def usage_names(self) -> tuple[str, ...]:
        """Names of the per-spacecraft actuator-usage integrals (e.g. delta-v), recorded as signals."""
        return ()

    def usage_shape(self) -> tuple[int, ...]:
        """Shape of every usage integral (default ``(count,)``; e.g. ``(count, axes)`` per axis)."""
        return (self.count,)

    def usage_rates(self, t: jax.Array, x: PyTree, command: jax.Array) -> dict[str, jax.Array]:
        """Rates of the usage integrals (integrated with the plant), each of shape :meth:`usage_shape`."""
        return {}

    def outputs(self, t: jax.Array, x: PyTree, inputs: TruthInputs) -> dict[str, jax.Array]:
        """Recorded true-state signals (declared by :meth:`signals`)."""
        return {}

    def sensed_state(self, x: PyTree) -> PyTree:
        """The view of the truth state that sensors measure (default: the state itself). A plant whose
        state is not in the formation frame (e.g. inertial orbits) returns here the layout relative-state
        sensors read (``{"q": (N, 6)}`` in LVLH), so every sensor built for that layout works on it."""
        return x

    def position(self, x: PyTree) -> jax.Array | None:
        """True (N, 3) position in the formation frame [m] (None for rotational plants); used only
        for evaluation (the ``position_error`` record) and the admissible set, never by the flight side."""
        return None

    def angular_rate(self, x: PyTree) -> jax.Array | None:
        """True (N, 3) body angular rate [rad/s] (None for translational plants); used only for the
        admissible set (``simulation.max_rate``)."""
        return None

    def euler_pitch(self, x: PyTree) -> jax.Array | None:
        """(N,) middle angle of a 3-2-1 Euler-angle attitude state [rad], whose kinematics are singular at
        +-pi/2 (None when the attitude is not held as Euler angles); admissible set only
        (``simulation.max_pitch``)."""
        return None

    def velocity(self, x: PyTree) -> jax.Array | None:
        """True (N, 3) velocity in the formation frame [m/s] (None when not applicable); used only for
        the admissible set."""
        return None


class Reference(_Kind):
    """An autonomous reference (virtual chief orbit): integrated ahead of the spacecraft at every step
    (its stage values are shared by the whole formation and by every run of a batch)."""

    kind: ClassVar[str] = "reference"

    def initial_state(self) -> PyTree:
        return None

    def rate(self, r: PyTree) -> PyTree:
        return None

    def values(self, r: PyTree) -> PyTree:
        """Quantities the plant (and the flight side) need from the reference state ``r``."""
        return None


class Sensors(_Kind):
    kind: ClassVar[str] = "sensors"
    #: True: :meth:`noise` receives the step's key itself and splits it into its own streams (the
    #: plant's process noise then uses a key folded from it); False: one half of the step key's split
    splits_step_key: ClassVar[bool] = False

    def noise(self, key: jax.Array) -> PyTree:
        """Measurement noise for one step (held over the step)."""
        return None

    def measure(self, t: jax.Array, x: PyTree, inputs: SensorInputs) -> PyTree:  # pragma: no cover
        raise NotImplementedError


class Network(_Kind):
    """Communication between spacecraft: graph, delays, histories of transmitted messages."""

    kind: ClassVar[str] = "network"
    delayed: ClassVar[bool] = False

    def initial_state(self, messages0: PyTree) -> PyTree:
        return None

    def receive(self, t: jax.Array, state: PyTree, inputs: NetworkInputs) -> PyTree:
        return None

    def push(self, state: PyTree, messages: PyTree) -> PyTree:
        return state

    def provides(self) -> frozenset[str]:
        """Every network delivers messages between spacecraft (``NoNetwork`` none)."""
        return frozenset({"inter-spacecraft-messages"})


class Estimator(_Kind):
    """Observer / FDI: discrete update once per step from flight inputs."""

    kind: ClassVar[str] = "estimator"
    #: True: a navigation filter -- its estimate has the layout of the sensors' measurement and the
    #: controller reads it in place of the measurement (and no other estimate)
    navigation: ClassVar[bool] = False

    def initial_state(self, measurement0: PyTree) -> PyTree:
        return None

    def predict(self, t: jax.Array, state: PyTree, command: jax.Array, dt: float) -> PyTree:
        """Time update over [t, t + dt] with the controller's command held over the step (called after
        the control step; flight side: the command, not the applied output). Default: none."""
        return state

    def update(self, t: jax.Array, state: PyTree, inputs: FlightInputs) -> tuple[PyTree, PyTree]:
        """``(state, estimate)`` at t_k; the signals recorded at t_k are those of this update (the
        estimate the step uses)."""
        return state, None

    def outputs(self, t: jax.Array, state: PyTree, estimate: PyTree) -> dict[str, jax.Array]:
        return {}


class Supervisor(_Kind):
    """Discrete decisions (mode switches, reconfiguration, membership)."""

    kind: ClassVar[str] = "supervisor"

    def initial_state(self) -> PyTree:
        return None

    def update(self, t: jax.Array, state: PyTree, inputs: FlightInputs) -> tuple[PyTree, PyTree]:
        """``(state, decision)`` at t_k: the decision in force over [t_k, t_{k+1})."""
        return state, None

    def outputs(self, t: jax.Array, state: PyTree, decision: PyTree) -> dict[str, jax.Array]:
        return {}


class Controller(_Kind):
    """Formation / attitude law. ``sampled = True``: evaluated once per step and held (zero-order
    hold); otherwise evaluated at every RK stage with its states integrated with the plant.

    :meth:`output` returns ``(command, state_derivative, outputs)``; for a sampled controller
    ``state_derivative`` is the *next* controller state instead of a derivative."""

    kind: ClassVar[str] = "controller"
    quantity: ClassVar[str] = "force"
    #: compile batches of loops with this law with XLA's fast-compile preset (:mod:`formation_ftc.sim.runtime.xla`):
    #: worth it only for a step with many operations per spacecraft; measured, not assumed
    batch_fast_compile: ClassVar[bool] = False

    @property
    def sampled(self) -> bool:
        return False

    def initial_state(self) -> PyTree:
        return None

    def desired_position_at(self, exogenous: PyTree) -> jax.Array | None:
        """The (N, 3) desired position [m] contained in this controller's time signals (None if it has
        no position objective); the loop records ``position_error = true position - desired``."""
        return None

    def message(self, t: jax.Array, inputs: FlightInputs) -> PyTree:
        """What each spacecraft transmits (e.g. its sliding variable); None: nothing."""
        return None

    def output(
        self, t: jax.Array, state: PyTree, inputs: FlightInputs
    ) -> tuple[jax.Array, PyTree, dict[str, jax.Array]]:  # pragma: no cover
        raise NotImplementedError


class Actuator(_Kind):
    """Allocation, faults and saturation on the truth side: command -> applied output."""

    kind: ClassVar[str] = "actuator"

    def initial_state(self) -> PyTree:
        return None

    def apply(self, t: jax.Array, command: jax.Array, inputs: ActuatorInputs) -> jax.Array:
        return command

    def update(
        self, t: jax.Array, state: PyTree, command: jax.Array, inputs: ActuatorInputs
    ) -> PyTree:
        """Discrete actuator state after the step (e.g. a stuck thruster's frozen value)."""
        return state

    def outputs(
        self, t: jax.Array, command: jax.Array, inputs: ActuatorInputs
    ) -> dict[str, jax.Array]:
        """Recorded truth-side actuator signals (e.g. the true effectiveness)."""
        return {}


#: slot name (the base's ``kind``) -> required base class, in slot order
KIND_SLOTS: dict[str, type] = {
    base.kind: base
    for base in (Plant, Reference, Sensors, Network, Estimator, Supervisor, Controller, Actuator)
}


# --------------------------------------------------------------------------------------------------
# "Nothing there" components
# --------------------------------------------------------------------------------------------------
@component
class NoReference(Reference):
    """No reference orbit (the plant is autonomous in its own frame)."""


@component
class PerfectSensors(Sensors):
    """The measurement is the true state (no noise)."""

    def measure(self, t, x, inputs):
        return x

    def provides(self) -> frozenset[str]:
        return frozenset({"plant-state-measurement"})


@component
class NoNetwork(Network):
    """No communication."""

    def provides(self) -> frozenset[str]:
        return frozenset()


@component
class NoEstimator(Estimator):
    """No observer / FDI."""


@component
class NoSupervisor(Supervisor):
    """No discrete decisions."""


@component
class IdealActuator(Actuator):
    """Applied output = command."""


class Evaluation(_Kind):
    """Evaluation signals: functions of one sample's recorded signals (truth and flight side), e.g.
    formation-error measures. They are recorded and feed metrics like any signal; the flight side never
    sees them. Listed in :attr:`ClosedLoop.evaluations <formation_ftc.sim.loop.ClosedLoop>`, evaluated
    in order (a later one may read an earlier one's signals)."""

    kind: ClassVar[str] = "evaluation"

    def outputs(self, signals: dict[str, jax.Array]) -> dict[str, jax.Array]:
        return {}


def tree_take(tree: PyTree, j: int) -> PyTree:
    """Entry ``j`` of every leaf's leading axis.

    Parameters
    ----------
    tree : pytree
        Arrays with a common leading axis (e.g. one entry per spacecraft or per run).
    j : int
        Index along that axis.

    Returns
    -------
    pytree
        The same structure with ``a[j]`` for every leaf ``a``.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.sim.components import tree_take
    >>> t = tree_take({"q": np.arange(6.0).reshape(3, 2), "m": np.array([10.0, 20.0, 30.0])}, 1)
    >>> t["q"], float(t["m"])
    (array([2., 3.]), 20.0)
    """
    return jax.tree_util.tree_map(lambda a: a[j], tree)
