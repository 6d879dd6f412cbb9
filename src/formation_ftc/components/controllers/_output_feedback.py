"""What the output-feedback formation-keeping laws of Gui et al. 2022 share (``gui2022-lof2tc``,
``gui2022-cof2tc``): the nominal orbit they track, their common section and builder, and the CARE
design; and free drift (no control).

How the flight side's CW design meets a plant it was not designed for:

* **On-board model.** The nominal orbit q0(t) is the free motion of the linear Clohessy-Wiltshire model
  with a mean motion ``mean_motion`` [rad/s] (default: sqrt(mu / a^3) of the ``[reference]`` orbit,
  known on board; without either the loop is refused: it needs ``reference-orbit``).
* **Acceleration -> force.** The laws work in accelerations [m/s^2]. On a force-driven plant the
  command is scaled by the nominal masses known on board, ``f_i = m_i^nom u_i`` [N]
  (:mod:`~formation_ftc.components.controllers._acceleration_to_force`); ``nominal_mass`` defaults
  to 100 kg each (a stated nominal value, never the plant's masses).
* **Gains.** ``gains = "printed"`` uses the K given in the section (the paper's printed gain),
  ``gains = "care"`` the CARE (34) with Q = care_q_scale I6, R = I3 at the on-board mean motion.
* **Tracking error.** The loop records ``position_tracking_error`` and ``velocity_tracking_error``
  (norms of the measured tracking error e_y).

Each law reads only :class:`~formation_ftc.sim.components.FlightInputs`: the measured (N, 6) relative
state (the capability ``relative-state-measurement``), the fault estimate of an estimator
(``estimate["fault"]``, zero without one) and its own time signal, the nominal orbit. On a
torque-driven plant the law stays an acceleration law, which the loop refuses naming both parts.
"""

from __future__ import annotations

import functools
from typing import Any, Literal

import jax.numpy as jnp
import numpy as np
from pydantic import Field, model_validator

from formation_ftc.components._flight_defaults import NOMINAL_MASS
from formation_ftc.components._registry import BuildContext, builder_input
from formation_ftc.components._sections import nominal_masses, onboard_mean_motion
from formation_ftc.components.estimators.iterative_learning_observer import (
    ONBOARD_MEAN_MOTION,
    Gain3x6,
    Vec6,
)
from formation_ftc.config.base import StrictModel
from formation_ftc.core.dynamics.cw import cw_free_motion
from formation_ftc.sim.components import Controller, FlightInputs, Signal, component, static
from formation_ftc.sim.contract import STATE, as_float

__all__ = ["NominalOrbitTracking", "OutputFeedbackSection", "care_solution"]


@component
class NominalOrbitTracking(Controller):
    """Base of the sampled output-feedback laws: the nominal orbit q0(t) = Phi(t) q0(0) of the CW free
    motion (28) (mean motion ``mean_motion`` [rad/s], ``desired_state`` q0(0) (N, 6) [m, m/s]) as the
    controller's own time signal, and the tracking error e_y = y0 - y = q0 - y (29) with C = I6.
    ``hold_desired``: q0(t) = q0(0) held fixed instead (slots fixed in LVLH, which are not free CW motion
    unless purely along-track: the force that holds them is then, for the law, an unmodelled
    disturbance)."""

    quantity = "acceleration"

    count: int = static()
    mean_motion: Any = 0.0  # [rad/s]
    desired_state: Any = 0.0  # q0(0), (N, 6) [m, m/s]
    hold_desired: bool = static(default=False)
    #: built without a mean motion (none stated, no [reference] orbit): a placeholder the loop refuses
    mean_motion_missing: bool = static(default=False)

    @property
    def sampled(self) -> bool:
        return True  # u_k held over the step (zero-order hold)

    def exogenous(self, t):
        if self.hold_desired:
            # fixed slots (same shape and dtype as (28))
            return {"q0": self.desired_state + 0.0 * t}
        return {"q0": cw_free_motion(self.mean_motion, self.desired_state, t)}  # (28)

    def desired_position_at(self, exogenous):
        return exogenous["q0"][:, :3]

    def tracking(self, inputs: FlightInputs):
        """(q0, e_y, F_hat) from the flight inputs."""
        q0 = inputs.exogenous["q0"]
        F_hat = jnp.zeros((self.count, 3)) if inputs.estimate is None else inputs.estimate["fault"]
        return q0, q0 - inputs.measurement, F_hat  # (29)

    def signals(self):
        return (
            Signal(
                "desired_state",
                STATE,
                "m, m s-1",
                "nominal orbit q0 (28) (positions [m], velocities [m s-1])",
                "LVLH",
            ),
            Signal(
                "tracking_error",
                STATE,
                "m, m s-1",
                "measured tracking error e_y = q0 - y (29)",
                "LVLH",
            ),
        )

    def output(self, t, state, inputs):  # pragma: no cover - subclasses define the law
        raise NotImplementedError

    def needs(self) -> dict[str, str]:
        out = {"relative-state-measurement": "track its nominal orbit (e_y = q0 - y)"}
        if self.mean_motion_missing:
            out["reference-orbit"] = (
                "take the mean motion of its CW model from it (or state controller.mean_motion)"
            )
        return out


@functools.lru_cache(maxsize=16)
def care_solution(n: float, q_scale: float):
    """The CARE (34) with Q = q_scale I6, R = I3 on the CW model of mean motion n (K = B^T P1); cached.

    Parameters
    ----------
    n : float
        Mean motion of the on-board CW model [rad/s].
    q_scale : float
        Q = q_scale I6 [-].

    Returns
    -------
    CareSolution
        P1 and K (:class:`~formation_ftc.design.riccati.CareSolution`).

    Examples
    --------
    >>> sol = care_solution(1.078e-3, 4e-5)
    >>> round(float(sol.K[0, 0]), 4), round(float(sol.K[0, 3]), 4)  # Gui2022's printed K: 0.0063, 0.1127
    (0.0063, 0.1127)
    """
    from formation_ftc.core.dynamics.cw import cw_matrices
    from formation_ftc.design.riccati import solve_care

    A, B = cw_matrices(n)
    return solve_care(A, B, q_scale * np.eye(6), np.eye(3))


class OutputFeedbackSection(StrictModel):
    """The fields the Gui2022 output-feedback laws share: the nominal orbit, the gain K and the
    on-board CW model and masses."""

    desired_state: list[Vec6] = Field(
        description=(
            "q0(0) of each spacecraft's nominal orbit (28), CW free motion on board [m, m/s] (one row each)."
        )
    )
    desired_motion: Literal["natural", "hold"] = builder_input(
        "natural",
        description=(
            "'natural': q0(t) is the CW free motion (28) from desired_state; 'hold': desired_state held fixed "
            "in LVLH (slots that are not free motion: the holding force is then an unmodelled disturbance)."
        ),
    )
    gains: Literal["printed", "care"] = builder_input(
        "printed",
        description=(
            "K: 'printed' as given, or 'care' = B^T P1 from the CARE (34) at the on-board mean motion."
        ),
    )
    K: Gain3x6 = Field(None, description="Gain K (3x6) [1/s^2, 1/s] (gains = 'printed').")
    care_q_scale: float = builder_input(
        4e-5, gt=0, description="Q = care_q_scale I6 of the CARE (34) [-] (gains = 'care')."
    )
    mean_motion: float | None = Field(None, gt=0, description=ONBOARD_MEAN_MOTION)
    nominal_mass: float | list[float] | None = builder_input(
        None,
        description=(
            "On-board masses m_nom [kg], f = m_nom u on a force-driven plant (default 100 kg each, a stated nominal "
            "value: never the plant's masses); the force conversion's nominal_mass (none on an "
            "acceleration-driven plant)."
        ),
    )

    @model_validator(mode="after")
    def _printed_given(self):
        if self.gains == "printed" and self.K is None:
            raise ValueError("K: required with gains = 'printed' (or set gains = 'care')")
        return self


def _output_feedback_fields(sec: OutputFeedbackSection, ctx: BuildContext) -> dict[str, Any]:
    """The fields of :class:`NominalOrbitTracking` (and K, B^+ H) from a law's section: the gain K as
    printed or from the CARE (34) at the on-board mean motion (without one, a placeholder the loop
    refuses: it needs ``reference-orbit``).

    Parameters
    ----------
    sec : OutputFeedbackSection
        The law's validated section.
    ctx : BuildContext
        The build's context (the spacecraft count, the ``[reference]`` orbit).

    Returns
    -------
    dict
        Keyword arguments of the law's component.
    """
    from formation_ftc.core.dynamics.cw import cw_matrices

    N = ctx.count
    if len(sec.desired_state) != N:
        raise ValueError(
            f"controller.desired_state: {len(sec.desired_state)} rows for {N} spacecraft"
        )
    n = onboard_mean_motion(sec.mean_motion, ctx.section("reference"))
    if sec.gains == "printed":
        K = np.asarray(sec.K, float)
    else:  # the CARE at the on-board mean motion (a placeholder without one)
        K = np.zeros((3, 6)) if n is None else care_solution(n, sec.care_q_scale).K
    _, B = cw_matrices(0.0 if n is None else n)
    BpB = np.linalg.pinv(B) @ B  # B^+ H with H = B (and B^+ E with E = B)
    return dict(
        count=N,
        mean_motion=as_float(0.0 if n is None else n),
        desired_state=as_float(sec.desired_state),
        K=as_float(K),
        BpH=as_float(BpB),
        hold_desired=sec.desired_motion == "hold",
        mean_motion_missing=n is None,
    )


def _on_plant(law: Controller, sec: OutputFeedbackSection, ctx: BuildContext) -> Controller:
    """The acceleration law as is on an acceleration-driven plant, f = m_nom u on a force-driven one;
    any other plant keeps the law unwrapped so the loop refuses the pair naming both. The tracking
    error norms go to ``ctx.evaluations``.

    Parameters
    ----------
    law : Controller
        The acceleration law.
    sec : OutputFeedbackSection
        Its section (the stated ``nominal_mass``).
    ctx : BuildContext
        The build's context (the built plant).

    Returns
    -------
    Controller
        The law the loop flies.
    """
    from formation_ftc.components.controllers._acceleration_to_force import force_from_acceleration
    from formation_ftc.components.evaluations._signal_arithmetic import PartNorm

    for part, lo, hi, units in (("position", 0, 3, "m"), ("velocity", 3, 6, "m s-1")):
        name, long_name = f"{part}_tracking_error", f"||{part} part of e_y = q0 - y||"
        norm = PartNorm(name, "tracking_error", lo, hi, units=units, long_name=long_name)
        ctx.evaluations.append(norm)
    if ctx.plant.quantity == "force":
        masses = nominal_masses(
            sec.nominal_mass, NOMINAL_MASS, ctx.count, "controller.nominal_mass"
        )
        return force_from_acceleration(law, as_float(masses))
    return law
