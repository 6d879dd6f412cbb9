"""Supervisor ``hierarchical``: the high-level (HL) supervisor of Azizi & Khorasani 2009 (Sec. I-IV) as a
discrete-event system with the modes {Nominal, LLFR-active, FLFR-active}.

Events and guards, evaluated once per control step k, branch-free (``jnp.where``) so the machine runs
inside ``lax.scan`` and under ``vmap``:

* Nominal -> LLFR on "fault estimated": the fault estimate b_hat has reached the supervisor
  (``k >= k_estimated``); the low level then allocates with b_hat (eq. (3)). The component passes
  either a scripted step or, fed by a fault detector in the loop, the current step once the detector
  has alarmed (``fault_information = "estimator"``).
* LLFR -> FLFR on "mission bound violated": the *measured* max |e_ij| exceeds e_s for
  ``confirm_steps`` consecutive steps (a dwell counter that rejects single noisy samples), monitoring
  only from ``monitor_start`` on and only if FLFR is enabled (``flfr``). The formation level then
  raises the weight alpha_k of the partially recovered satellite to the value designed offline by
  eq. (9)/(11) (:mod:`formation_ftc.design.flfr`).

FLFR is absorbing. The state also counts the mode changes and the steps spent in FLFR (the switch
step counts as the first).

The supervisor selects the allocation mode of a law that has them (capability ``allocation-modes``,
the ``azizi2009-llfr`` law, whose desired polygon and faulty spacecraft it reads), monitors the chain
errors it reads (``chain-outputs``) and, with ``fault_information = "estimator"``, switches to LLFR at
the first detection of the loop's fault detector (``fault-alarm``, e.g. ``residual-fdi``).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Literal, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from pydantic import Field

from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.components.sensors.chain_relative import chain_layout
from formation_ftc.config.base import StrictModel
from formation_ftc.core.polygon_formation import chain_difference, rotating_polygon
from formation_ftc.sim.components import (
    CompositionError,
    Evaluation,
    FlightInputs,
    Signal,
    Supervisor,
    component,
    static,
)
from formation_ftc.sim.contract import as_float

__all__ = [
    "NOMINAL",
    "LLFR",
    "FLFR",
    "MODE_NAMES",
    "HlState",
    "initial_state",
    "transition",
    "HierarchicalSupervisor",
    "HierarchicalSection",
    "ThresholdFlag",
    "FAULT_INFORMATION",
    "NEVER",
]

NOMINAL, LLFR, FLFR = 0, 1, 2
MODE_NAMES = ("Nominal", "LLFR", "FLFR")
#: where the "fault estimated" event comes from (``HierarchicalSupervisor.fault_information``)
FAULT_INFORMATION = ("scripted", "estimator")
#: a step index no run reaches: the event has not happened
NEVER = np.iinfo(np.int64).max


# ------------------------------------------------------------------------------------------ equations
class HlState(NamedTuple):
    """mode (int), consecutive-violation counter, number of mode changes, steps spent in FLFR and
    that time [s]."""

    mode: jax.Array
    violations: jax.Array
    mode_changes: jax.Array
    flfr_steps: jax.Array
    time_in_flfr: jax.Array


def initial_state() -> HlState:
    """The machine's start: Nominal mode, all counters zero.

    Returns
    -------
    HlState
        The initial state.

    Examples
    --------
    >>> int(initial_state().mode) == NOMINAL
    True
    """
    z = jnp.asarray(0, jnp.int64)
    return HlState(jnp.asarray(NOMINAL, jnp.int64), z, z, z, time_in_flfr=jnp.asarray(0.0))


def transition(
    state: HlState,
    k,
    error_max,
    k_estimated,
    e_s,
    confirm_steps,
    monitor_start,
    flfr_enabled,
    dt: float,
) -> HlState:
    """The machine at step ``k`` given the measured max |e_ij|; its ``mode`` is the mode of step k.

    Parameters
    ----------
    state : HlState
        The state after step k - 1.
    k : int
        The step index.
    error_max : float
        Measured max |e_ij| at step k [m].
    k_estimated : int
        Step at which the fault estimate reaches the supervisor.
    e_s : float
        Mission error bound [m].
    confirm_steps : int
        Consecutive violations needed for FLFR.
    monitor_start : int
        First monitored step.
    flfr_enabled : bool
        Whether FLFR may be entered.
    dt : float
        The control step [s] (for the time spent in FLFR).

    Returns
    -------
    HlState
        The state of step k.

    Examples
    --------
    >>> s = transition(initial_state(), 0, 0.0, 0, 0.03, 1, 0, True, 0.1)
    >>> int(s.mode) == LLFR  # the estimate is there at step 0
    True
    >>> int(transition(s, 1, 0.05, 0, 0.03, 1, 0, True, 0.1).mode) == FLFR  # 0.05 m > e_s
    True
    """
    mode = state.mode
    # Nominal -> LLFR: fault estimate available
    to_llfr = (mode == NOMINAL) & (k >= k_estimated)
    mode1 = jnp.where(to_llfr, LLFR, mode)
    # LLFR -> FLFR: sustained violation of the mission bound e_s (monitoring needs LLFR before step k)
    monitoring = (mode == LLFR) & (k >= monitor_start) & flfr_enabled
    violated = monitoring & (error_max > e_s)
    violations = jnp.where(violated, state.violations + 1, 0)
    to_flfr = violated & (violations >= jnp.maximum(confirm_steps, 1))
    mode2 = jnp.where(to_flfr, FLFR, mode1)
    changes = state.mode_changes + (mode2 != mode).astype(jnp.int64)
    flfr_steps = jnp.where(mode2 == FLFR, state.flfr_steps + 1, 0)
    return HlState(mode2, violations, changes, flfr_steps, time_in_flfr=flfr_steps * dt)


# ------------------------------------------------------------------------------------------ component
@component
class HierarchicalSupervisor(Supervisor):
    """Discrete-event HL supervisor, updated once per control step k (t_k = t0 + k dt):

    * Nominal -> LLFR when the fault estimate has arrived (step ``k_estimated``);
    * LLFR -> FLFR when the measured max |e_ij| (chain relative position errors, from the
      ``"position"`` chain output minus the desired rotating polygon of side ``side`` [m] at ``omega``
      [rad/s]) exceeds ``e_s`` [m] for ``confirm_steps`` consecutive steps, from step
      ``monitor_start`` on, if ``flfr`` (FLFR enabled).

    Decision: the mode (int). Records ``mode``, ``mode_changes`` and ``time_in_flfr`` [s] (time spent
    in FLFR, the switch step counted as the first step).

    ``fault_information`` says where the "fault estimated" event comes from: ``"scripted"`` (default)
    -- the step ``k_estimated``; ``"estimator"`` -- the first step at which the estimate of the
    estimator in the loop reports ``estimate["detected"]`` (any element true, e.g. the latched alarm of
    :class:`~formation_ftc.components.estimators.residual_fdi.ResidualFdi`); ``k_estimated`` is then
    not read. The chain positions are the chain sensors' measurement, or, given the (N, 6)
    relative-state measurement (e.g. ``lvlh-relative-state`` sensors), formed on board,
    ``y_ij = rho_{i+1} - rho_i``.
    """

    count: int = static()
    n_axes: int = static()
    side: Any  # [m]
    omega: Any  # [rad/s]
    e_s: Any  # mission error bound [m]
    k_estimated: Any  # step at which the fault estimate reaches the supervisor (int)
    confirm_steps: Any  # consecutive violations needed (int)
    monitor_start: Any  # first monitored step (int)
    flfr: Any  # bool: FLFR enabled
    fault_information: str = static(default="scripted")  # "scripted" | "estimator"

    def __post_init__(self) -> None:
        if self.fault_information not in FAULT_INFORMATION:
            raise CompositionError(
                f"supervisor HierarchicalSupervisor: fault_information = {self.fault_information!r}, "
                f"expected one of {', '.join(FAULT_INFORMATION)}"
            )

    def needs(self) -> dict[str, str]:
        out = {
            "chain-outputs": "monitor the chain errors",
            "allocation-modes": "select the law's allocation mode",
        }
        if self.fault_information == "estimator":
            out["fault-alarm"] = (
                "switch to LLFR at the first detection (supervisor.fault_information = 'estimator')"
            )
        return out

    def initial_state(self):
        return initial_state()

    def update(self, t, state, inputs: FlightInputs):
        k, dt = inputs.step.k, inputs.step.dt
        rd, _, _ = rotating_polygon(t, self.count, self.n_axes, self.side, self.omega)
        e = self._chain_position(inputs.measurement) - chain_difference(rd)
        e_max, k_est = jnp.max(jnp.abs(e)), self._k_estimated(k, inputs.estimate)
        new = transition(
            state, k, e_max, k_est, self.e_s, self.confirm_steps, self.monitor_start, self.flfr, dt
        )
        return new, new.mode

    def _chain_position(self, measurement):
        """Measured chain relative positions (N-1, axes) [m]."""
        if isinstance(measurement, Mapping):
            return measurement["position"]
        return chain_difference(measurement[:, : self.n_axes])

    def _k_estimated(self, k, estimate):
        """Step of the "fault estimated" event: the scripted step, or (estimator mode) this step once
        the estimator reports a detection (never before)."""
        if self.fault_information == "scripted":
            return self.k_estimated
        if not isinstance(estimate, Mapping) or "detected" not in estimate:
            if estimate is None:
                got = "no estimate"
            elif isinstance(estimate, Mapping):
                got = f"an estimate without 'detected' (keys: {', '.join(map(str, estimate))})"
            else:
                got = f"an estimate of type {type(estimate).__name__}, not a mapping"
            raise CompositionError(
                "supervisor HierarchicalSupervisor: fault_information = 'estimator' switches to LLFR "
                f"when the estimator reports estimate['detected'], but the loop's estimator gives {got}"
            )
        detected = jnp.any(jnp.asarray(estimate["detected"]))
        return jnp.where(detected, k, NEVER)

    def signals(self):
        modes = ", ".join(f"{j} = {m}" for j, m in enumerate(MODE_NAMES))
        in_flfr = "time spent in FLFR (the switch step counts as one step)"
        return (
            Signal("mode", (), "1", f"HL supervisor mode: {modes}"),
            Signal("mode_changes", (), "1", "number of mode changes so far"),
            Signal("time_in_flfr", (), "s", in_flfr),
        )

    def outputs(self, t, state, decision):
        return {
            "mode": state.mode,
            "mode_changes": state.mode_changes,
            "time_in_flfr": state.time_in_flfr,
        }


# ------------------------------------------------------------------------------------------ section
class HierarchicalSection(StrictModel):
    """HL supervisor: Nominal -> LLFR when the fault estimate arrives (at ``estimate_time``, or when the
    estimator in the loop detects the fault); LLFR -> FLFR when the measured max |e_ij| exceeds e_s
    (for ``confirm_time``, from ``monitor_start`` on)."""

    e_s: float = Field(gt=0, description="Mission error bound e_s on the chain errors [m].")
    flfr: bool = Field(True, description="Allow the switch to FLFR [-].")
    fault_information: Literal["scripted", "estimator"] = Field(
        "scripted",
        description="Source of the 'fault estimated' event (Nominal -> LLFR): 'scripted' -- at "
        "estimate_time, for the fault stated in controller.faulty_spacecraft; 'estimator' -- at the "
        "first step the [estimator]'s estimate reports 'detected' (e.g. residual-fdi), whatever the "
        "controller states [-].",
    )
    estimate_time: float = builder_input(
        0.0,
        ge=0,
        description="Time the fault estimate reaches the supervisor (fault_information = "
        "'scripted') [s].",
    )
    confirm_time: float = builder_input(
        0.0, ge=0, description="A violation must persist this long before FLFR [s]."
    )
    monitor_start: float = builder_input(
        0.0,
        ge=0,
        description="Start of the monitoring of e_s [s] (the component's monitor_start is its step "
        "index).",
    )
    settle_time: float = builder_input(
        20.0, ge=0, description="The flag flfr_settled rises this long after the switch [s]."
    )


@component
class ThresholdFlag(Evaluation):
    """``name = source >= threshold`` (a boolean signal, e.g. a metric gate)."""

    name: str = static()
    source: str = static()
    long_name: str = static(default="")
    threshold: Any = 0.0

    def signals(self):
        return (Signal(self.name, (), "1", self.long_name or f"{self.source} >= threshold"),)

    def outputs(self, signals):
        return {self.name: jnp.logical_not(jnp.asarray(signals[self.source]) < self.threshold)}


def _steps(time: float, dt: float) -> int:
    return int(round(time / dt))


def _build(sec: HierarchicalSection, ctx: BuildContext) -> HierarchicalSupervisor:
    """The supervisor of a validated ``[supervisor] type = "hierarchical"`` section. The desired
    polygon and the faulty spacecraft are the law's (its ``[controller]`` section); a law without them
    gives a placeholder (validation refuses it: it provides no ``allocation-modes``)."""
    _, axes = chain_layout(ctx)
    estimated = sec.fault_information == "estimator"
    c = ctx.section("controller")
    faulty: int | None = getattr(c, "faulty_spacecraft", None)
    n, dt = ctx.count, ctx.dt
    never = ctx.scenario.simulation.n_steps + 1
    known = faulty is not None
    identified = getattr(c, "fault_estimate", "stated") == "estimator"  # FLFR on the isolated one
    if sec.flfr and faulty is not None and not 1 < faulty < n:
        raise ValueError(
            f"supervisor.flfr needs an interior faulty spacecraft (2..{n - 1}) on the chain; "
            f"controller.faulty_spacecraft = {faulty}"
        )
    settled = as_float((_steps(sec.settle_time, dt) + 0.5) * dt)
    long_name = "FLFR active for longer than supervisor.settle_time"
    ctx.evaluations.append(ThresholdFlag("flfr_settled", "time_in_flfr", long_name, settled))
    return HierarchicalSupervisor(
        count=n,
        n_axes=axes,
        side=as_float(getattr(c, "side", 0.0)),
        omega=as_float(getattr(c, "omega", 0.0)),
        e_s=as_float(sec.e_s),
        k_estimated=np.asarray(
            _steps(sec.estimate_time, dt) if known and not estimated else never, np.int64
        ),
        confirm_steps=np.asarray(_steps(sec.confirm_time, dt), np.int64),
        monitor_start=np.asarray(_steps(sec.monitor_start, dt), np.int64),
        flfr=np.asarray(bool(sec.flfr and (known or identified))),
        fault_information=sec.fault_information,
    )


register(
    "supervisor",
    "hierarchical",
    HierarchicalSection,
    _build,
    "Azizi2009 HL supervisor: Nominal -> LLFR on the fault estimate, LLFR -> FLFR when |e_ij| > e_s",
)
