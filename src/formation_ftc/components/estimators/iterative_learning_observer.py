"""Estimator ``iterative-learning-observer``: the iterative learning observer (ILO) of Gui et al. 2022,
eq. (5), reconstructing thruster faults on an on-board Clohessy-Wiltshire model, one per spacecraft.

Continuous-time law (5), with e_y = y - C q_hat::

    q_hat_dot = A q_hat + B u + H F_hat + L1 e_y + gamma sgn(e_y)       (sign term: E002-02)
    F_hat(t)  = Q1 F_hat(t - tau) + Q2 L2 e_y(t)                         (learning update)

Discrete implementation: at sample k (t_k = k dt) the learning update is evaluated
first, ``F_hat_k = Q1 F_hat_{k-m} + Q2 L2 e_y,k`` (:func:`ilo_learning_update`) with ``m = tau/dt`` an
integer number of steps, the past estimates read from a delay line (:mod:`formation_ftc.core.delay_line`,
prehistory ``F_hat(t) = F_hat(-tau)`` for t < 0); then ``q_hat`` is propagated by forward Euler with
``e_y``, ``u`` and ``F_hat_k`` held over the step (:func:`ilo_propagate`). Without the sign term
(``gamma`` term dropped) this is the earlier ILO of the paper's ref. [25].

Every function acts on the last axis and broadcasts over leading axes (one row per spacecraft).
Units: q in [m, m/s], u, F in m/s^2 (per unit mass, E002-03), L1 [1/s], L2 [1/s] (velocity rows),
gamma [m/s^2], dt and tau [s]. Shapes: A (n, n), B (n, m_u), H (n, m), L1 (n, p), L2 (m, p), Q1 (m,)
diagonal, Q2 and gamma scalars; C = I (y = q).

How the flight side's CW design meets a plant it was not designed for:

* **On-board model.** The internal model is the linear CW model with a mean motion ``mean_motion``
  [rad/s] (default: sqrt(mu / a^3) of the ``[reference]`` orbit, known on board; without either the
  loop is refused: it needs ``reference-orbit``). On a nonlinear plant about an elliptic reference the
  difference between the true relative acceleration and the CW model -- eccentricity, nonlinearity and
  the plant's disturbance -- enters as an unknown input in the velocity channel, exactly where the
  thruster faults enter (H = B): F_hat reconstructs the fault *plus* that model mismatch.
* **Force loops.** On a force-driven plant the time update divides the loop's force command by the
  nominal masses known on board, ``u_i = f_i / m_i^nom``
  (:class:`~formation_ftc.components.estimators._acceleration_model.AccelerationModelEstimator`);
  ``nominal_mass`` defaults to the controller's ``nominal_mass``, else 100 kg each (never the plant's).
  The observer starts from its stated ``initial_estimate`` (default zero).
* **Gains.** ``gains = "printed"`` uses the L1, L2 given in the section; ``gains = "lmi"`` re-solves the
  LMIs (8), (27) and the pole-region LMI at the on-board mean motion (``lmi_scale``: the free scale of
  these homogeneous LMIs).
* **Fault in acceleration units.** With ``thruster-bias`` faults the loop records
  ``fault_acceleration`` = F_i / m_i (force loops: the true fault per unit true mass) and
  ``fault_error`` = F - F_hat [m/s^2].

Needs the measured (N, 6) relative state (``relative-state-measurement``: a translational plant with
exact or ``relative-state`` sensors); provides the fault estimate (``thruster-fault-estimate``).
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Annotated, Any, Literal

import jax
import jax.numpy as jnp
import numpy as np
from pydantic import AfterValidator, Field, field_validator, model_validator

from formation_ftc.components._flight_defaults import NOMINAL_MASS
from formation_ftc.components._registry import BuildContext, builder_input, component_type, register
from formation_ftc.components._sections import Vec3, nominal_masses, onboard_mean_motion
from formation_ftc.components.estimators.relative_navigation_filter import (
    RelativeNavigationSection,
    filtered,
)
from formation_ftc.config.base import StrictModel
from formation_ftc.core.delay_line import delay_init, delay_push, delay_read
from formation_ftc.core.dynamics.cw import cw_matrices_jax
from formation_ftc.core.linear import matvec
from formation_ftc.sim.components import Estimator, FlightInputs, Signal, component, static
from formation_ftc.sim.contract import STATE, VEC, as_float

__all__ = [
    "ilo_learning_update",
    "ilo_correction",
    "ilo_propagate",
    "learning_steps",
    "IterativeLearningObserver",
    "IloSection",
    "ilo_lmi_design",
]

Vec6 = tuple[float, float, float, float, float, float]
#: description of the on-board mean motion (the ILO's and the Gui2022 laws' sections)
ONBOARD_MEAN_MOTION = (
    "Mean motion n of the on-board CW model [rad/s] (default: sqrt(mu / a^3) of the reference orbit; "
    "required without one)."
)


# ------------------------------------------------------------------------------------- equations
def learning_steps(tau: float, dt: float, field: str = "learning_interval") -> int:
    """``tau / dt`` as an integer >= 1 (learning laws with t - tau need tau to be an integer number of
    steps).

    Parameters
    ----------
    tau : float
        Learning interval [s].
    dt : float
        Step [s].
    field : str, optional
        The field's name, for the error.

    Returns
    -------
    int
        m = tau / dt.

    Raises
    ------
    ValueError
        tau is not a positive integer multiple of dt (naming ``field``).

    Examples
    --------
    >>> learning_steps(0.2, 0.05)
    4
    """
    if not (tau > 0 and dt > 0):
        raise ValueError(f"{field} = {tau} s and simulation.dt = {dt} s must be > 0")
    m = round(tau / dt)
    if m < 1 or abs(m * dt - tau) > 1e-9 * max(tau, dt):
        raise ValueError(
            f"{field} = {tau:g} s is not an integer multiple of simulation.dt = {dt:g} s "
            f"(tau/dt = {tau / dt:.6g}); the learning law reads F_hat(t - tau) from the step grid, so "
            f"tau must be k*dt with an integer k >= 1"
        )
    return int(m)


def ilo_learning_update(F_past: jax.Array, e_y: jax.Array, Q1, Q2, L2) -> jax.Array:
    """The learning update of (5): ``F_hat_k = Q1 F_hat_{k-m} + Q2 L2 e_y,k`` [m/s^2].

    Parameters
    ----------
    F_past : jax.Array, shape (..., m)
        F_hat_{k-m} [m/s^2].
    e_y : jax.Array, shape (..., p)
        Output error y - q_hat [m, m/s].
    Q1 : array_like, shape (m,)
        Diagonal of Q1 [-].
    Q2 : float
        Learning gain [-].
    L2 : array_like, shape (m, p)
        Learning gain [1/s].

    Returns
    -------
    jax.Array
        F_hat_k, shape (..., m) [m/s^2].

    Examples
    --------
    >>> import numpy as np
    >>> F = ilo_learning_update(np.ones(3), np.ones(6), np.full(3, 0.5), 2.0, np.ones((3, 6)))
    >>> np.asarray(F).tolist()  # 0.5 * 1 + 2 * 6
    [12.5, 12.5, 12.5]
    """
    return Q1 * F_past + Q2 * matvec(L2, e_y)  # (5), learning update


def ilo_correction(e_y: jax.Array, L1, gamma, sign_term: bool) -> jax.Array:
    """Output injection ``L1 e_y + gamma sgn(e_y)`` (sgn(0) = 0) [m/s, m/s^2].

    Parameters
    ----------
    e_y : jax.Array, shape (..., p)
        Output error [m, m/s].
    L1 : array_like, shape (n, p)
        Observer gain [1/s].
    gamma : float
        Sign-term gain [m/s^2].
    sign_term : bool
        Include gamma sgn(e_y) (E002-02).

    Returns
    -------
    jax.Array
        The injection, shape (..., n).

    Examples
    --------
    >>> import numpy as np
    >>> np.asarray(ilo_correction(np.array([2.0, -1.0]), np.eye(2), 0.5, True)).tolist()
    [2.5, -1.5]
    """
    corr = matvec(L1, e_y)
    if sign_term:
        corr = corr + gamma * jnp.sign(e_y)  # E002-02: 6-vector sign term (C = I)
    return corr


def ilo_propagate(
    q_hat: jax.Array,
    u: jax.Array,
    F_hat: jax.Array,
    e_y: jax.Array,
    A,
    B,
    H,
    L1,
    gamma,
    dt: float,
    sign_term: bool,
) -> jax.Array:
    """Forward-Euler step of ``q_hat`` over [t_k, t_k + dt] with u, F_hat_k, e_y,k held [m, m/s]::

        q_hat_{k+1} = q_hat_k + dt (A q_hat_k + B u_k + H F_hat_k + L1 e_y,k + gamma sgn e_y,k)   # (5)

    Parameters
    ----------
    q_hat : jax.Array, shape (..., n)
        State estimate q_hat_k [m, m/s].
    u : jax.Array, shape (..., m_u)
        Commanded acceleration [m/s^2].
    F_hat : jax.Array, shape (..., m)
        Fault estimate [m/s^2].
    e_y : jax.Array, shape (..., p)
        Output error [m, m/s].
    A, B, H : array_like
        Model matrices (n, n), (n, m_u), (n, m).
    L1 : array_like, shape (n, p)
        Observer gain [1/s].
    gamma : float
        Sign-term gain [m/s^2].
    dt : float
        Step [s].
    sign_term : bool
        Include gamma sgn(e_y).

    Returns
    -------
    jax.Array
        q_hat_{k+1}, shape (..., n).

    Examples
    --------
    >>> import numpy as np
    >>> q = ilo_propagate(np.zeros(2), np.ones(1), np.zeros(1), np.zeros(2), np.zeros((2, 2)),
    ...                   np.array([[0.0], [1.0]]), np.zeros((2, 1)), np.zeros((2, 2)), 0.0, 0.5, False)
    >>> np.asarray(q).tolist()
    [0.0, 0.5]
    """
    qh_dot = (
        matvec(A, q_hat)
        + matvec(B, u)
        + matvec(H, F_hat)
        + ilo_correction(e_y, L1, gamma, sign_term)
    )  # (5), observer
    return q_hat + dt * qh_dot


# ------------------------------------------------------------------------------------ component
@component
class IterativeLearningObserver(Estimator):
    """ILO (5) on a CW model per spacecraft: reconstructs the thruster faults F [m/s^2] from the
    measured (N, 6) relative state y (C = I6) and the commanded acceleration u.

    Measurement update at t_k (:meth:`update`)::

        e_y,k = y_k - q_hat_k;   F_hat_k = Q1 F_hat_{k-m} + Q2 L2 e_y,k                    # (5)

    time update over the step (:meth:`predict`, forward Euler with u_k, F_hat_k, e_y,k held)::

        q_hat_{k+1} = q_hat_k + dt (A q_hat_k + B u_k + H F_hat_k + L1 e_y,k + gamma sgn e_y,k)   # (5)

    with A = A(n) and B = H = [0; I3] of the CW model (mean motion ``mean_motion`` [rad/s]); the learning
    interval tau = m dt (``learning_steps`` = m); ``sign_term = False`` drops gamma sgn (ILO of ref. [25]).
    Gains: L1 (6, 6) [1/s], L2 (3, 6) [1/s], Q1 (3,) [-], Q2 [-], gamma [m/s^2].

    The estimate (``FlightInputs.estimate`` of the controller) is ``{"fault": F_hat_k (N, 3), "state":
    q_hat_k (N, 6), "output_error": e_y,k (N, 6)}``. Recorded: ``estimate``, ``fault_estimate``,
    ``estimation_error`` (e_y = y - q_hat), ``estimation_error_sign`` (sgn e_y) and
    ``fault_estimate_mean``, the mean of F_hat over the ``mean_steps`` steps before the sample (with
    the sign term F_hat chatters with a period of 2 steps, which decimated samples would alias).
    """

    count: int = static()
    mean_motion: Any = 0.0  # n of the CW model [rad/s]
    L1: Any = 0.0  # (6, 6) [1/s]
    L2: Any = 0.0  # (3, 6) [1/s]
    Q1: Any = 1.0  # (3,) diagonal [-]
    Q2: Any = 1.0  # [-]
    gamma: Any = 0.0  # [m/s^2]
    initial_estimate: Any = 0.0  # q_hat(0), (N, 6) [m, m/s]
    fault_prehistory: Any = 0.0  # F_hat(t), t < 0, (N, 3) [m/s^2]
    learning_steps: int = static(default=1)  # m = tau / dt
    sign_term: bool = static(default=True)
    #: steps averaged by fault_estimate_mean (the record interval)
    mean_steps: int = static(default=1)
    #: built without a mean motion (none stated, no [reference] orbit): a placeholder the loop refuses
    mean_motion_missing: bool = static(default=False)

    def initial_state(self, measurement0):
        n = self.count
        return dict(
            q_hat=jnp.asarray(self.initial_estimate, dtype=jnp.float64),
            F_hist=delay_init(self.fault_prehistory, self.learning_steps),
            F_hat=jnp.zeros((n, 3)),
            e_y=jnp.zeros((n, 6)),
            mean_sum=jnp.zeros((n, 3)),
            mean_last=jnp.zeros((n, 3)),
            mean_n=jnp.zeros((), dtype=jnp.int32),
        )

    def update(self, t, state, inputs: FlightInputs):
        e_y = inputs.measurement - state["q_hat"]  # C = I6
        F_hat = ilo_learning_update(
            delay_read(state["F_hist"], self.learning_steps), e_y, self.Q1, self.Q2, self.L2
        )  # (5)
        n = state["mean_n"]
        first, full = n == 0, n == self.mean_steps
        reset = first | full
        mean_last = jnp.where(
            first, F_hat, jnp.where(full, state["mean_sum"] / self.mean_steps, state["mean_last"])
        )
        new = dict(
            q_hat=state["q_hat"],
            F_hist=delay_push(state["F_hist"], F_hat, self.learning_steps),
            F_hat=F_hat,
            e_y=e_y,
            mean_sum=jnp.where(reset, 0.0, state["mean_sum"]) + F_hat,
            mean_last=mean_last,
            mean_n=jnp.where(reset, 1, n + 1).astype(jnp.int32),
        )
        return new, self._estimate(new)

    def predict(self, t, state, command, dt):
        A, B = cw_matrices_jax(self.mean_motion)
        q, F, e = state["q_hat"], state["F_hat"], state["e_y"]
        # (5), H = B
        q_hat = ilo_propagate(q, command, F, e, A, B, B, self.L1, self.gamma, dt, self.sign_term)
        return {**state, "q_hat": q_hat}

    def _estimate(self, state):
        return {"fault": state["F_hat"], "state": state["q_hat"], "output_error": state["e_y"]}

    def signals(self):
        return (
            Signal(
                "estimate",
                STATE,
                "m, m s-1",
                "ILO state estimate q_hat (positions [m], velocities [m s-1])",
                "LVLH",
            ),
            Signal(
                "estimation_error",
                STATE,
                "m, m s-1",
                "e_y = y - q_hat (= q - q_hat with exact measurements)",
                "LVLH",
            ),
            Signal("estimation_error_sign", STATE, "1", "sgn(e_y), the switching term of the ILO"),
            Signal("fault_estimate", VEC, "m s-2", "reconstructed fault F_hat", "LVLH"),
            Signal(
                "fault_estimate_mean",
                VEC,
                "m s-2",
                "F_hat averaged over the record interval "
                "(removes the period-2-step chatter caused by the sign term)",
                "LVLH",
            ),
        )

    def outputs(self, t, state, estimate):
        return {
            "estimate": estimate["state"],
            "estimation_error": estimate["output_error"],
            "estimation_error_sign": jnp.sign(estimate["output_error"]),
            "fault_estimate": estimate["fault"],
            "fault_estimate_mean": state["mean_last"],
        }

    def needs(self) -> dict[str, str]:
        out = {"relative-state-measurement": "run its CW model on it (C = I6)"}
        if self.mean_motion_missing:
            out["reference-orbit"] = (
                "take the mean motion of its CW model from it (or state estimator.mean_motion)"
            )
        return out

    def provides(self) -> frozenset[str]:
        return frozenset({"thruster-fault-estimate"})


# -------------------------------------------------------------------------------------- section
def _matrix(rows: int, columns: int) -> AfterValidator:
    """The check of a gain field: None or a finite ``rows`` x ``columns`` matrix given as a list of
    rows."""

    def check(value):
        if value is None:
            return None
        arr = np.asarray(value, dtype=float)
        if arr.shape != (rows, columns):
            raise ValueError(
                f"expected a {rows}x{columns} matrix (list of rows), got shape {arr.shape}"
            )
        if not np.all(np.isfinite(arr)):
            raise ValueError("entries must be finite")
        return arr.tolist()

    return AfterValidator(check)


#: gains L1 (6 x 6) and K, L2 (3 x 6), each optional
Gain6x6 = Annotated[list[list[float]] | None, _matrix(6, 6)]
Gain3x6 = Annotated[list[list[float]] | None, _matrix(3, 6)]


@functools.lru_cache(maxsize=16)
def ilo_lmi_design(n: float, lam: float, center: float, radius: float):
    """The ILO design (P, Y, L1, L2) of the LMIs (8), (27) and the pole region S(c, r) on the CW model
    of mean motion n (C = I6, H = B), normalised P >= I; cached by input (an offline design).

    Parameters
    ----------
    n : float
        Mean motion of the on-board CW model [rad/s].
    lam : float
        lambda of (27) [-].
    center : float
        Centre c of the pole region [1/s] (< 0).
    radius : float
        Radius r of the pole region [1/s].

    Returns
    -------
    IloLmiDesign
        The design (:class:`~formation_ftc.design.lmi.IloLmiDesign`).

    Examples
    --------
    >>> des = ilo_lmi_design(1.078e-3, 1e-8, -5.0, 2.0)
    >>> des.L1.shape, des.L2.shape
    ((6, 6), (3, 6))
    """
    from formation_ftc.core.dynamics.cw import cw_matrices
    from formation_ftc.design.lmi import design_ilo_gains

    A, B = cw_matrices(n)
    return design_ilo_gains(A, np.eye(6), B, lam=lam, disk_center=center, disk_radius=radius)


class IloSection(StrictModel):
    """Iterative learning observer (5) on an on-board CW model, one per spacecraft."""

    gains: Literal["printed", "lmi"] = builder_input(
        "printed",
        description=(
            "'printed': L1, L2 as given; 'lmi': solve (8), (27) and the pole-region LMI at the on-board mean motion."
        ),
    )
    L1: Gain6x6 = Field(None, description="Observer gain L1 (6x6) [1/s] (gains = 'printed').")
    L2: Gain3x6 = Field(None, description="Learning gain L2 (3x6) [1/s] (gains = 'printed').")
    lmi_lambda: float = builder_input(1e-8, gt=0, description="lambda of (27) [-] (gains = 'lmi').")
    disk_center: float = builder_input(
        -5.0, lt=0, description="Centre c of the pole region S(c, r) [1/s] (gains = 'lmi')."
    )
    disk_radius: float = builder_input(
        2.0, gt=0, description="Radius r of the pole region S(c, r) [1/s] (gains = 'lmi')."
    )
    lmi_scale: float = builder_input(
        1.0,
        gt=0,
        description=(
            "Free scale s of the homogeneous LMIs: (P, Y, L2) -> s (P, Y, L2) after the normalised solve "
            "(P >= I) [-] (gains = 'lmi')."
        ),
    )
    Q1: Vec3 = Field(description="Diagonal of Q1, each in (0, 1] [-].")
    Q2: float = Field(gt=0, description="Learning gain Q2 [-].")
    gamma: float = Field(ge=0, description="Sign-term gain gamma [m/s^2].")
    sign_term: bool = Field(
        True, description="Include gamma sgn(e_y) (false: the ILO without the sign term)."
    )
    mu: float = builder_input(
        0.001, gt=0, description="mu of Theorem 1, eta = 1 + mu [-] (for `check`; Gui2022: 0.001)."
    )
    gamma1: float = builder_input(
        0.0193, gt=0, description="gamma_1 of (10) [-] (for `check`; Gui2022: 0.0193)."
    )
    beta: float = builder_input(
        1.0, gt=0, description="beta of (17), Q2 = 1/(beta eta) [-] (for `check`; Gui2022: 1)."
    )
    learning_interval: float = builder_input(
        gt=0, description="tau: a positive integer multiple of simulation.dt [s]."
    )
    mean_motion: float | None = Field(None, gt=0, description=ONBOARD_MEAN_MOTION)
    nominal_mass: float | list[float] | None = builder_input(
        None,
        description=(
            "On-board masses m_nom [kg] dividing a force command into the model's acceleration (default: the "
            "controller's nominal_mass, else 100 kg each; never the plant's masses); the force "
            "conversion's nominal_mass (none on an acceleration-driven plant)."
        ),
    )
    initial_estimate: Vec6 | list[Vec6] = Field(
        (0.0,) * 6,
        description=(
            "q_hat(0), the observer's initial estimate [m, m/s]: one row for every spacecraft or one per spacecraft "
            "(default: a zero initial estimate, a stated value, never the plant's initial state)."
        ),
    )

    navigation: RelativeNavigationSection | None = builder_input(
        None,
        description=(
            "A relative-navigation-filter table: the observer reads the filter's estimate in place "
            "of the raw measurement and the law flies on it (its nominal_mass defaults to the "
            "observer's masses). None: both read the raw measurement."
        ),
    )

    @field_validator("navigation", mode="before")
    @classmethod
    def _navigation_type(cls, v):
        if isinstance(v, dict) and "type" in v:  # the table as it stands on its own, with its type
            if v["type"] != "relative-navigation-filter":
                raise ValueError(
                    f"type = {v['type']!r}: the observer runs on a relative-navigation-filter"
                )
            v = {k: x for k, x in v.items() if k != "type"}
        return v

    @field_validator("Q1")
    @classmethod
    def _q1(cls, v):
        for k, s in enumerate(v):
            if not 0 < s <= 1:
                raise ValueError(f"Q1[{k}] = {s}: each entry must be in (0, 1]")
        return v

    @model_validator(mode="after")
    def _printed_given(self):
        if self.gains == "printed" and (self.L1 is None or self.L2 is None):
            missing = " and ".join(f for f in ("L1", "L2") if getattr(self, f) is None)
            raise ValueError(f"{missing}: required with gains = 'printed' (or set gains = 'lmi')")
        return self

    def design_at(self, n: float):
        """The LMI design (gains = 'lmi') on the CW model of mean motion n [rad/s], scaled by
        ``lmi_scale`` (an :class:`~formation_ftc.design.lmi.IloLmiDesign`)."""
        from formation_ftc.core.dynamics.cw import cw_matrices

        des = ilo_lmi_design(n, self.lmi_lambda, self.disk_center, self.disk_radius)
        if self.lmi_scale == 1.0:
            return des
        from formation_ftc.design.lmi import rescale_design

        A, B = cw_matrices(n)
        return rescale_design(des, self.lmi_scale, A, np.eye(6), B)

    def gains_at(self, n: float) -> tuple[np.ndarray, np.ndarray]:
        """(L1, L2) used on the CW model of mean motion n [rad/s]."""
        if self.gains == "printed":
            return np.asarray(self.L1, float), np.asarray(self.L2, float)
        des = self.design_at(n)
        return des.L1, des.L2


def _actuator_provides(ctx: BuildContext) -> frozenset[str]:
    """The capabilities the loop's ``[actuator]`` provides (none without one): its component built from
    its section on a scratch context (numpy only; nothing it adds to the context is kept).

    Parameters
    ----------
    ctx : BuildContext
        The build's context (the scenario, the built plant).

    Returns
    -------
    frozenset of str
        Names of :data:`~formation_ftc.sim.contract.CAPABILITIES`.
    """
    name = ctx.scenario.labels().get("actuator")
    entry = None if name is None else component_type("actuator", name)
    if entry is None:
        return frozenset()
    scratch = dataclasses.replace(ctx, evaluations=[], metrics=[])
    return frozenset(entry.build(ctx.section("actuator"), scratch).provides())


def _build(sec: IloSection, ctx: BuildContext) -> Estimator:
    """The estimator of a validated ``[estimator] type = "iterative-learning-observer"`` section: the
    ILO, wrapped for a force loop (the command per unit nominal mass); the truth-side signals of the
    fault error go to ``ctx.evaluations`` (with ``thruster-bias`` faults)."""
    from formation_ftc.components.estimators._acceleration_model import AccelerationModelEstimator
    from formation_ftc.components.evaluations._per_unit_mass import PerUnitMass
    from formation_ftc.components.evaluations._signal_arithmetic import SignalSum

    m = learning_steps(sec.learning_interval, ctx.dt, "estimator.learning_interval")
    n = onboard_mean_motion(sec.mean_motion, ctx.section("reference"))
    # without a mean motion: a placeholder without a design (validation names the missing orbit)
    L1, L2 = (np.zeros((6, 6)), np.zeros((3, 6))) if n is None else sec.gains_at(n)
    N = ctx.count
    q_hat0 = np.asarray(sec.initial_estimate, dtype=float)
    if q_hat0.ndim == 1:
        q_hat0 = np.broadcast_to(q_hat0, (N, 6)).copy()
    elif q_hat0.shape != (N, 6):
        raise ValueError(
            f"estimator.initial_estimate: {q_hat0.shape[0]} rows for {N} spacecraft (give one row or {N})"
        )
    ilo = IterativeLearningObserver(
        count=N,
        mean_motion=as_float(0.0 if n is None else n),
        L1=as_float(L1),
        L2=as_float(L2),
        Q1=as_float(sec.Q1),
        Q2=as_float(sec.Q2),
        gamma=as_float(sec.gamma),
        initial_estimate=as_float(q_hat0),  # stated, never the plant's initial state
        fault_prehistory=as_float(np.zeros((N, 3))),
        learning_steps=m,
        sign_term=sec.sign_term,
        mean_steps=int(ctx.scenario.simulation.record_every),
        mean_motion_missing=n is None,
    )
    force_loop = ctx.plant.quantity == "force"
    # the masses that turned the law's acceleration into the force: the ILO's own, else the law's
    law_mass = getattr(ctx.section("controller"), "nominal_mass", None)
    stated = law_mass if sec.nominal_mass is None else sec.nominal_mass
    mass = nominal_masses(stated, NOMINAL_MASS, N, "estimator.nominal_mass")
    est: Estimator = (
        AccelerationModelEstimator(inner=ilo, nominal_mass=as_float(mass)) if force_loop else ilo
    )
    est = filtered(est, sec.navigation, ctx, mass)
    if "thruster-bias-faults" in _actuator_provides(ctx):  # F recorded as the signal fault
        fault = "fault"
        true_mass = getattr(ctx.section("plant"), "mass", None)
        if force_loop and true_mass is not None:
            ctx.evaluations.append(
                PerUnitMass(
                    "fault_acceleration",
                    "fault",
                    mass=as_float(true_mass),
                    long_name="true thruster fault per unit true mass F_i / m_i",
                    frame="LVLH",
                )
            )
            fault = "fault_acceleration"
        ctx.evaluations.append(
            SignalSum(
                "fault_error",
                (("+", fault), ("-", "fault_estimate")),
                units="m s-2",
                long_name="e_F = F - F_hat (F_hat also holds the model mismatch)",
                frame="LVLH",
            )
        )
    return est


register(
    "estimator",
    "iterative-learning-observer",
    IloSection,
    _build,
    "Gui2022 iterative learning observer (5): thruster-fault reconstruction on a CW model",
)
