"""The JAX-free part of the component contract: what a scenario section needs while it is validated.

:class:`CompositionError` and :func:`as_float` are used by the catalog modules
(``formation_ftc.methods.composed.catalog_*``), which declare their TOML sections at import time and
build their components only when a loop is made. Keeping these names here (numpy only) lets
``formation-ftc show`` and ``formation-ftc schema`` load every catalog without importing JAX.
:mod:`formation_ftc.sim.components` re-exports both, so ``from formation_ftc.sim.components import
CompositionError, as_float`` keeps working; :mod:`formation_ftc.sim.metrics` re-exports the names of
the metric reductions, which ``[[metrics]]`` sections check.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

__all__ = [
    "CompositionError",
    "Capability",
    "CAPABILITIES",
    "capability",
    "as_float",
    "REDUCTIONS",
    "BLOCK_REDUCTIONS",
    "STAGE_REDUCTIONS",
    "SPACECRAFT_REDUCTIONS",
]

#: time reductions: name -> meaning
REDUCTIONS = {
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
