"""The JAX-free part of the component contract: what a scenario section needs while it is validated.

:class:`CompositionError` and :func:`as_float` are used by the component homes
(``formation_ftc.components.<kind>.<name>``), which declare their TOML sections at import time and
build their components only when a loop is made; :data:`CAPABILITIES` names what a part may need or
provide; :class:`Condition` is what a component states for ``formation-ftc check`` (re-exported by
:mod:`formation_ftc.registry`). Keeping these names here (numpy only) lets ``formation-ftc show`` and
``formation-ftc schema`` load every home without importing JAX. :mod:`formation_ftc.sim.components`
re-exports the first two, so ``from formation_ftc.sim.components import CompositionError, as_float``
keeps working; :mod:`formation_ftc.sim.metrics` re-exports the names of the metric reductions, which
``[[metrics]]`` sections check.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any, NamedTuple, NoReturn

import numpy as np

__all__ = [
    "CompositionError",
    "Capability",
    "CAPABILITIES",
    "capability",
    "as_float",
    "Condition",
    "BASES",
    "CERTIFYING_BASES",
    "REDUCTIONS",
    "BLOCK_REDUCTIONS",
    "STAGE_REDUCTIONS",
    "SPACECRAFT_REDUCTIONS",
]

#: time reductions: name -> meaning
REDUCTIONS = {
    "stl": "robustness of the signal temporal logic formula `formula` on the recorded samples "
    "(formation_ftc.sim.stl; >= 0: it holds) [units of its atoms]",
    "max": "maximum over the window",
    "min": "minimum over the window",
    "final": "last value in the window",
    "mean": "mean over the samples in the window",
    "integral": "rectangle-rule integral over the window (value at t_k times dt) [signal unit x s]",
    "at": "value at the first sample with t >= start",
    "settle": "first time after which the value stays below `threshold` (NaN if it ends above) [s]",
    "settle_delay": "`settle` measured from the window start [s] (0 when it never was at or above)",
    "rms": "root mean square over the samples in the window, the horizon sample excluded (as `integral`)",
    "stage_integral": "integral over the steps [t_k, t_k + dt] inside the window, integrated with the plant "
    "(the RK4 stage values; rectangle rule for an exact-step plant) [signal unit x s]",
    "stage_root_mean": "sqrt(stage_integral / (end - start)): with square = True, the RMS over the window",
    "first": "time of the first sample at or above `threshold` (NaN if there is none) [s]",
    "last": "value at the horizon (the run's last sample; window ignored), read once after the loop: no "
    "per-step cost, unlike `final`; NaN for a run that left its admissible set before the horizon",
    "block_rms": "low-pass RMS: the samples in the window (the horizon sample excluded) cut into consecutive "
    "blocks of `block` steps from the first one; RMS over the complete blocks of each block's mean "
    "(a boxcar filter of `block` steps, decimated; an incomplete last block is dropped)",
    "block_dev_rms": "RMS of the value minus the mean of its block (blocks as `block_rms`): the amplitude of "
    "what varies faster than `block` steps, e.g. a chatter",
}
#: time reductions over blocks of ``Metric.block`` steps
BLOCK_REDUCTIONS = ("block_rms", "block_dev_rms")
#: time reductions integrated at the integrator's stages (need a signal evaluated at every RK stage:
#: plant, controller and actuator outputs, ``command``, ``applied``)
STAGE_REDUCTIONS = ("stage_integral", "stage_root_mean")
#: how spacecraft are combined before the time reduction
SPACECRAFT_REDUCTIONS = ("each", "max", "mean", "sum", "none", "range")
#: dims of a recorded per-spacecraft 3-vector and of a per-spacecraft state (:class:`Signal` dims)
VEC = ("spacecraft", "axis")
STATE = ("spacecraft", "component")


class CompositionError(ValueError):
    """Two components that cannot work together (raised before any computation)."""


# its public name (tracebacks, doctests, pickles): formation_ftc.sim.components, which re-exports it
CompositionError.__module__ = "formation_ftc.sim.components"


class Capability(NamedTuple):
    """Something one part of a closed loop gives the others (:data:`CAPABILITIES`)."""

    meaning: str  # what the part provides, as a noun phrase
    provided_by: str  # which component types provide it (for the error message)


#: Everything a component may declare it ``needs`` or ``provides`` (``Component.needs()``,
#: ``Component.provides()``): one table, so that a declaration names an entry of it and the error of a
#: loop that lacks it says who would provide it. :meth:`~formation_ftc.sim.loop.ClosedLoop.validate`
#: checks every need against what the loop's parts provide.
CAPABILITIES: dict[str, Capability] = {
    "reference-orbit": Capability(
        "a reference orbit known on board", 'a [reference] section, e.g. type = "keplerian"'
    ),
    # --- attitude (quaternion and Euler-angle plants, their sensors, allocation, laws, FDIs, scores)
    "quaternion-attitude-state": Capability(
        "a plant whose state is {omega (N,3), q (N,4)}: body rate and quaternion, vector part first",
        'plant type = "quaternion-rigid-body" or "attitude-truth"',
    ),
    "lvlh-attitude": Capability(
        "the attitude relative to LVLH, recorded as attitude_lvlh (a plant on an orbit)",
        'plant type = "attitude-truth"',
    ),
    "euler-angle-attitude-state": Capability(
        "a plant whose state is {q (N,3), w (N,3)}: 3-2-1 Euler angles [theta, phi, psi] and body "
        "rates, driven by the generalised torque conjugate to the angles",
        'plant type = "euler-angle-attitude"',
    ),
    "plant-state-measurement": Capability(
        "the plant's state as the measurement", "no [sensors] section (exact, unchanged)"
    ),
    "euler-angle-measurement": Capability(
        "3-2-1 Euler angles and body rates as the measurement, {q (N,3), w (N,3)}",
        'sensors type = "quaternion-euler" on a quaternion plant ("quaternion-rigid-body", '
        '"attitude-truth"), or plant type = "euler-angle-attitude" without [sensors]',
    ),
    "generalised-torque-actuation": Capability(
        "an actuator applying the generalised torque conjugate to the 3-2-1 Euler angles to the plant",
        'actuator type = "euler-torque-allocation", or "fault-battery" with euler_allocation = true, '
        'or plant type = "euler-angle-attitude" (driven by it)',
    ),
    "euler-angle-law": Capability(
        "a law in 3-2-1 Euler angles commanding the conjugate generalised torque (records its "
        "tracking and synchronisation errors)",
        'controller type = "networked-el-hinf"',
    ),
    "scripted-actuator-faults": Capability(
        "additive actuator faults stated in the scenario, in the law's generalised channels",
        'actuator type = "euler-torque-allocation" with faults',
    ),
    # --- translational (CW / relative-LVLH plants, graphs, formation laws, thruster faults, scores)
    "recorded-positions": Capability(
        "the spacecraft positions recorded as the signal position (N, 3) [m]",
        'a translational plant, e.g. type = "clohessy-wiltshire", "relative-lvlh" or "orbital-truth"',
    ),
    "applied-forces": Capability(
        "a plant driven by forces [N]",
        'plant type = "clohessy-wiltshire", "relative-lvlh" or "orbital-truth"',
    ),
    "true-masses": Capability(
        "the spacecraft's true masses [kg] (a plant with a mass field)",
        'plant type = "clohessy-wiltshire", "relative-lvlh" or "orbital-truth"',
    ),
    # --- chain, faults, navigation, truth (chain law and HL supervisor, fault battery, link loss,
    # navigation filter and residual FDI, orbital truth)
    "translational-state": Capability(
        "positions and velocities of the spacecraft in what sensors see (the (N, 6) relative state "
        "q, or positions r and velocities v)",
        'plant type = "clohessy-wiltshire", "relative-lvlh", "clohessy-wiltshire-zoh", '
        '"orbital-truth" or "double-integrator"',
    ),
    "lvlh-relative-state": Capability(
        "the (N, 6) LVLH relative state q = [position, velocity] in what sensors see",
        'plant type = "clohessy-wiltshire", "relative-lvlh", "clohessy-wiltshire-zoh" or '
        '"orbital-truth"',
    ),
    "spacecraft-pairs": Capability(
        "two or more spacecraft (a chain of relative pairs)", "a plant of two or more spacecraft"
    ),
    "stage-evaluation": Capability(
        "RK4 integration that evaluates the command at every stage",
        'plant type = "clohessy-wiltshire", "relative-lvlh", "orbital-truth", or '
        '"double-integrator" with integration = "rk4"',
    ),
    "chain-outputs": Capability(
        "relative positions and velocities on the chain pairs (1, 2), ..., (N-1, N) as the "
        "measurement",
        'sensors type = "chain-relative", or "lvlh-relative-state" (the chain outputs formed on '
        "board from the LVLH relative state)",
    ),
    "allocation-modes": Capability(
        "a law whose allocation has the modes Nominal / LLFR / FLFR",
        'controller type = "azizi2009-llfr"',
    ),
    "fault-alarm": Capability(
        "an estimate that reports a fault detection (estimate['detected'])",
        'estimator type = "residual-fdi"',
    ),
    "navigation-records": Capability(
        "the law flies on this estimator's navigation filter, which records its estimate, error "
        "covariance and normalised innovation squared (navigation_estimate, navigation_covariance, "
        "navigation_nis)",
        'estimator type = "relative-navigation-filter", or "residual-fdi" with fly_on_filter = true',
    ),
    "fault-identification": Capability(
        "an estimate of each actuator channel's effectiveness with its standard deviation and whether it "
        "is identified (estimate['effectiveness'], ['effectiveness_std'], ['identified'])",
        'estimator type = "residual-fdi" with identification = "rls"',
    ),
    "fdi-records": Capability(
        "a fault detector's latched alarm and isolated channel, recorded as fdi_detected and "
        "fdi_isolated in the actuator's channels",
        'estimator type = "residual-fdi" or "attitude-residual-fdi"',
    ),
    "true-actuator-fault": Capability(
        "the true fault of one actuator channel, recorded as fault_active and fault_channel",
        'actuator type = "fault-battery"',
    ),
    # --- learning, delays, switched (Gui2022's ILO and laws, Yang2013's translational and switched types)
    "relative-state-measurement": Capability(
        "the measured (N, 6) relative position and velocity y = [p, v] of every spacecraft",
        'no [sensors] on a translational plant (exact), or sensors type = "relative-state" or '
        '"lvlh-relative-state"',
    ),
    "thruster-fault-estimate": Capability(
        "an estimate F_hat (N, 3) of the thruster faults per unit mass (the estimate's fault)",
        'estimator type = "iterative-learning-observer"',
    ),
    "thruster-bias-faults": Capability(
        "thruster faults F(t) with onsets stated in the scenario, recorded as the signal fault",
        'actuator type = "thruster-bias"',
    ),
    "perturbation-signal": Capability(
        "the space perturbation d(t) of the plant recorded as the signal disturbance [m/s^2]",
        'plant type = "clohessy-wiltshire-zoh"',
    ),
    "inter-spacecraft-messages": Capability(
        "a network delivering the messages of the spacecraft each one references",
        'a [network] section, e.g. type = "graph" or "delayed-graph"',
    ),
    "switching-plan": Capability(
        "the prescribed mode sequence of a switched formation (switch times, members, state "
        "variation (10))",
        'supervisor type = "switching"',
    ),
    "error-state": Capability(
        "a plant whose state is the error state x_i = [e_R, e_V, e_omega, e_q, e_q4] (7) of every "
        "spacecraft, {x (N, 13)}",
        'plant type = "switched-formation"',
    ),
    "error-state-measurement": Capability(
        "the measured error state {translation (N, 6), omega (N, 3), q (N, 4)} of Yang2013 (7)",
        'sensors type = "tracking-error"',
    ),
    "velocity-gain-law": Capability(
        "a law (12) whose velocity gain K2 and stated mass M_i a controller fault corrupts",
        'controller type = "yang2013-force-torque"',
    ),
}


def capability(name: str) -> Capability:
    """The entry of :data:`CAPABILITIES` named ``name``.

    Parameters
    ----------
    name : str
        A capability's name.

    Returns
    -------
    Capability
        Its meaning and who provides it.

    Raises
    ------
    KeyError
        A name that is no capability (a declaration bug), listing the known names.

    Examples
    --------
    >>> capability("reference-orbit").meaning
    'a reference orbit known on board'
    """
    try:
        return CAPABILITIES[name]
    except KeyError:
        raise KeyError(
            f"capability {name!r} is not in formation_ftc.sim.contract.CAPABILITIES "
            f"(known: {', '.join(sorted(CAPABILITIES))})"
        ) from None


def as_float(x: Any) -> np.ndarray:
    """float64 array leaf (a numpy array: cheap to build; JAX converts it when the run is called).

    Parameters
    ----------
    x : array_like
        Numbers (any SI unit; unchanged).

    Returns
    -------
    numpy.ndarray
        ``x`` as float64.

    Examples
    --------
    >>> from formation_ftc.sim.components import as_float
    >>> as_float([1, 2])
    array([1., 2.])
    >>> as_float(3).dtype
    dtype('float64')
    """
    return np.asarray(x, dtype=np.float64)


#: How a condition's verdict was computed (:attr:`Condition.basis`).
BASES = ("exact", "verified", "sampled", "heuristic", "informative")
#: The bases whose computation may certify a condition (``holds=True``).
CERTIFYING_BASES = ("exact", "verified", "informative")


@dataclass(frozen=True)
class Condition:
    """One theorem / design condition evaluated before (or after) a run.

    ``holds`` is None when the condition cannot be evaluated for this scenario or when the computation
    could not prove it. ``required`` marks conditions the method's guarantee needs: ``formation-ftc
    check`` exits with 1 when one fails.

    ``basis`` (keyword, no default: every condition states it) says how the verdict was computed:

    * ``"exact"`` -- exact arithmetic, or floating point with a stated rounding margin;
    * ``"verified"`` -- a verified bound (interval arithmetic, a certificate re-checked in numpy);
    * ``"sampled"`` -- evaluated at sample points: a violation found is real, a pass is not a proof;
    * ``"heuristic"`` -- an estimate that is not a bound;
    * ``"informative"`` -- a number shown for the reader, not a requirement (``required=False``).

    ``holds=True`` is only allowed with ``exact``, ``verified`` or ``informative``; a sampled or
    heuristic computation that finds no violation reports ``holds=None`` ("unproven"). ``holds=False``
    is allowed with any basis.
    """

    name: str
    reference: str
    value: str
    requirement: str
    holds: bool | None
    required: bool = True
    detail: str = ""
    basis: str = field(kw_only=True)

    def __post_init__(self) -> None:
        def fail(problem: str) -> NoReturn:
            raise ValueError(f"condition {self.name!r}: {problem}")

        if self.basis not in BASES:
            fail(f"basis {self.basis!r} is not one of {', '.join(BASES)}")
        if self.holds is not None and not isinstance(self.holds, bool | np.bool_):
            fail(f"holds must be True, False or None, got {self.holds!r}")
        if self.basis == "informative" and self.required:
            fail("an informative condition cannot be required")
        if self.holds is not None and bool(self.holds) and self.basis not in CERTIFYING_BASES:
            fail(
                f"a {self.basis} computation cannot prove that it holds; report holds=None "
                "(unproven) when no violation is found"
            )

    @property
    def unproven(self) -> bool:
        """True when the condition was evaluated by sampling or a heuristic and no violation was found."""
        return self.holds is None and self.basis in ("sampled", "heuristic")

    def as_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {f.name: str(getattr(self, f.name)) for f in fields(self)}
        # the two non-text fields in their places (numpy bools too)
        out["holds"] = None if self.holds is None else bool(self.holds)
        out["required"] = bool(self.required)
        return out


# its public name (reprs, docs, pickles): formation_ftc.registry, which re-exports it
Condition.__module__ = "formation_ftc.registry"
