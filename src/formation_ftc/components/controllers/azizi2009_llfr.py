"""Controller ``azizi2009-llfr``: relative-output formation control on a chain of spacecraft pairs with
low-level fault recovery (LLFR) allocation whose weights the HL supervisor's mode selects, and the
offline FLFR weight design (Azizi & Khorasani 2009, Sec. II-IV, eqs. (3), (8)-(11)).

Per axis, the relative output of the chain pair (i, i+1) obeys ``e_ij'' = b_j u_j - b_i u_i + ...``; the
formation law asks for the relative acceleration::

    p_ij = xdd_ij^d - lambda1 e'_ij - lambda0 e_ij                               # Sec. II

and the allocation distributes it over the satellites with the weighted least-effort solution of
eq. (3), ``u = J_aug(alpha, b_hat)^-1 [p; 0] = M(alpha, b_hat) p``
(:func:`formation_ftc.design.allocation.allocation_matrix`). The HL supervisor's mode selects
(alpha, b_hat): Nominal (alpha, b), LLFR (alpha, b_hat), FLFR (alpha with alpha_k raised to the FLFR
weight, b_hat). The three matrices per axis are computed once per run. Units: e [m], e' [m/s], p and
xdd^d [m/s^2], u [m/s^2 per unit actuator gain].

How the law fits a plant it was not written for:

* it models each spacecraft as a double integrator ``x_i'' = b_i u_i`` (deep space): any other
  dynamics of the plant (orbital relative motion, disturbances) act on it as unmodelled accelerations;
* it commands accelerations u_i [m/s^2]. On a force-driven plant it is wrapped in
  :class:`~formation_ftc.components.controllers._acceleration_to_force.AccelerationToForce`:
  ``f_i = m_i^nom u_i`` with the flight side's ``nominal_mass`` [kg] (default 100 kg, a stated nominal
  value: never the plant's true masses);
* the desired formation is the law's own: a regular N-gon of side ``side`` [m] rotating at ``omega``
  [rad/s] in the plane of the plant frame's first two axes (LVLH radial / along-track for the relative
  plants), controlled through the N-1 chain outputs only (the centroid is not controlled);
* it reads the capability ``chain-outputs``: the chain outputs measured by ``chain-relative`` sensors,
  or formed on board from the (N, 6) LVLH relative state of ``lvlh-relative-state`` sensors; with
  ``sampling = "continuous"`` it needs ``stage-evaluation`` (a plant integrated by RK4). It provides
  ``allocation-modes`` (what the ``hierarchical`` supervisor selects).

Where the plant records positions, the law adds the true chain errors (the ``chain-errors``
evaluation) unless the scenario lists them.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import TYPE_CHECKING, Annotated, Any, Literal

import jax
import jax.numpy as jnp
import numpy as np
from pydantic import Field

from formation_ftc.components._flight_defaults import NOMINAL_MASS
from formation_ftc.components._registry import BuildContext, builder_input, per_spacecraft, register
from formation_ftc.components._sections import Masses, positive_values, section_floats
from formation_ftc.components.estimators.residual_fdi import isolated_effectiveness
from formation_ftc.components.sensors.chain_relative import chain_layout
from formation_ftc.components.supervisors.hierarchical import FLFR, LLFR, NOMINAL
from formation_ftc.config.base import StrictModel
from formation_ftc.core.polygon_formation import chain_difference, rotating_polygon
from formation_ftc.design.allocation import allocation_matrix
from formation_ftc.sim.components import Controller, FlightInputs, Signal, component, static
from formation_ftc.sim.contract import VEC, as_float

if TYPE_CHECKING:
    from formation_ftc.design.flfr import FlfrDesign

__all__ = [
    "ChainLlfrController",
    "ChainLlfrSection",
    "relative_output_law",
    "mode_allocation_matrices",
    "allocate",
    "law_gains",
    "flfr_design",
    "AXES",
    "DESIGN_HORIZON",
]

AXES = ("x", "y", "z")
#: horizon of the simulated supremum H_i of the FLFR design (several rotation periods) [s]
DESIGN_HORIZON = 300.0


# ------------------------------------------------------------------------------------------ equations
def relative_output_law(e, e_dot, xdd_desired, lambda0, lambda1) -> jax.Array:
    """p_ij = xdd_ij^d - lambda1 e'_ij - lambda0 e_ij [m/s^2] (Sec. II).

    Parameters
    ----------
    e, e_dot : array_like, shape (N-1, axes)
        Chain errors [m] and their rates [m/s].
    xdd_desired : array_like, shape (N-1, axes)
        Desired relative accelerations xdd_ij^d [m/s^2].
    lambda0, lambda1 : float
        Position [1/s^2] and velocity [1/s] gains.

    Returns
    -------
    jax.Array, shape (N-1, axes)
        The relative accelerations p_ij asked of the allocation [m/s^2].

    Examples
    --------
    >>> import numpy as np
    >>> relative_output_law(np.array([0.1]), np.array([0.01]), 0.0, 2.0, 3.0).round(12).tolist()
    [-0.23]
    """
    return xdd_desired - lambda1 * e_dot - lambda0 * e


def mode_allocation_matrices(alpha, alpha_flfr, k: int | jax.Array, b_nominal, b_hat) -> jax.Array:
    """Allocation matrices of the modes Nominal, LLFR, FLFR (eq. (3)).

    Parameters
    ----------
    alpha : array_like, shape (N,)
        LLFR weights alpha_i [-].
    alpha_flfr : float
        FLFR weight of satellite ``k`` [-].
    k : int
        0-based satellite whose weight FLFR raises.
    b_nominal, b_hat : array_like, shape (N, axes)
        Nominal and estimated actuator gains [-].

    Returns
    -------
    jax.Array, shape (3, axes, N, N-1)
        M(alpha, b) per mode (Nominal, LLFR, FLFR) and axis.

    Examples
    --------
    >>> import numpy as np
    >>> M = mode_allocation_matrices(np.ones(3), 4.0, 1, np.ones((3, 1)), np.ones((3, 1)))
    >>> M.shape
    (3, 1, 3, 2)
    """
    alpha = jnp.asarray(alpha)
    alpha_f = alpha.at[k].set(alpha_flfr)
    alphas = jnp.stack([alpha, alpha, alpha_f])
    # (3, N, axes)
    b_hats = jnp.stack([jnp.asarray(b_nominal), jnp.asarray(b_hat), jnp.asarray(b_hat)])
    return jax.vmap(lambda a, bh: jax.vmap(lambda bcol: allocation_matrix(a, bcol), in_axes=1)(bh))(
        alphas, b_hats
    )


def allocate(M, p) -> jax.Array:
    """u = M p per axis (eq. (3)).

    Parameters
    ----------
    M : array_like, shape (axes, N, N-1)
        Allocation matrix of each axis.
    p : array_like, shape (N-1, axes)
        Relative accelerations asked of the chain pairs [m/s^2].

    Returns
    -------
    jax.Array, shape (N, axes)
        Commands u_i [m/s^2 per unit actuator gain].

    Examples
    --------
    >>> import numpy as np
    >>> M = mode_allocation_matrices(np.ones(2), 1.0, 0, np.ones((2, 1)), np.ones((2, 1)))[1]
    >>> np.asarray(allocate(M, np.array([[1.0]]))).ravel().tolist()  # u_2 - u_1 = 1, u_1 + u_2 = 0
    [-0.5, 0.5]
    """
    return jnp.einsum("anm,ma->na", M, p)


# ------------------------------------------------------------------------------------------ component
@component
class ChainLlfrController(Controller):
    """Formation keeping of a rotating regular polygon on the chain of relative outputs::

        e_ij = y_ij - (x_j^d - x_i^d),   e'_ij likewise from the measured relative velocities
        p_ij = xdd_ij^d - lambda1 e'_ij - lambda0 e_ij                               (Sec. II)
        u    = M(alpha_mode, b_hat_mode) p                                           (eq. (3))

    reading the chain outputs: the
    :class:`~formation_ftc.components.sensors.chain_relative.ChainRelativeSensors` measurement
    (``"position"``/``"velocity"``, (N-1, axes)), or, given the (N, 6) LVLH relative-state measurement
    (``lvlh-relative-state`` sensors), the chain outputs formed on board from it,
    ``y_ij = q_{i+1} - q_i`` on the first ``n_axes`` position and velocity axes (the same law; the noise
    of a chain output is then that of two spacecraft's states). The decision of the HL supervisor (an
    integer mode: 0 Nominal, 1 LLFR, 2 FLFR) selects the allocation: Nominal (alpha, b), LLFR
    (alpha, b_hat), FLFR (alpha with alpha_k = ``alpha_flfr`` for satellite ``fault_index``, b_hat).
    Without a supervisor (no decision) the LLFR allocation is used. The three matrices per axis are
    computed once per run (controller state). With ``fault_estimate = "estimator"`` they are computed at
    every step from the estimator's fault identification instead: once the FDI has isolated a channel and
    identified its effectiveness, LLFR and FLFR allocate with ``b_hat = b * effectiveness`` on that
    channel (clipped to [0.05, 1]: :func:`~formation_ftc.components.estimators.residual_fdi.isolated_effectiveness`; the stated ``b_hat`` elsewhere) and FLFR raises the
    weight of the isolated spacecraft (``fault_index`` until an isolation). Desired formation: regular polygon of side ``side``
    [m] rotating at ``omega`` [rad/s] (:func:`formation_ftc.core.polygon_formation.rotating_polygon`).
    ``is_sampled``: u computed at t_k and held over the step; otherwise re-evaluated at every RK stage.
    Command u [m/s^2 per unit actuator gain].
    """

    lambda0: Any  # [1/s^2]
    lambda1: Any  # [1/s]
    alpha: Any  # (N,) allocation weights [-]
    alpha_flfr: Any  # FLFR weight of satellite fault_index [-]
    b: Any  # (N, axes) nominal actuator gains [-]
    b_hat: Any  # (N, axes) estimated actuator gains (LLFR) [-]
    side: Any  # [m]
    omega: Any  # [rad/s]
    fault_index: int = static(default=0)  # 0-based satellite whose weight FLFR raises
    fault_estimate: str = static(default="stated")  # "stated" or "estimator" (docstring)
    is_sampled: bool = static(default=True)
    frame: str = static(default="inertial")  # frame of the desired formation's axes (records only)

    @property
    def sampled(self) -> bool:
        return self.is_sampled

    @property
    def count(self) -> int:
        return int(np.shape(self.b_hat)[0])

    @property
    def n_axes(self) -> int:
        return int(np.shape(self.b_hat)[1])

    quantity = "acceleration"

    def needs(self) -> dict[str, str]:
        out = {"chain-outputs": "read the relative outputs it controls"}
        if self.fault_estimate == "estimator":
            out["fault-identification"] = (
                "allocate with the identified effectiveness of the isolated channel "
                "(controller.fault_estimate = 'estimator')"
            )
        if not self.is_sampled:
            out["stage-evaluation"] = (
                "re-evaluate its continuous command at the RK stages (sampling = 'continuous'; "
                "give the plant integration = 'rk4')"
            )
        return out

    def provides(self) -> frozenset[str]:
        return frozenset({"allocation-modes"})

    def desired(self, t):
        """Desired positions, velocities, accelerations (N, axes) at ``t`` [s]."""
        return rotating_polygon(t, self.count, self.n_axes, self.side, self.omega)

    def initial_state(self):
        return {
            "allocation": mode_allocation_matrices(
                self.alpha, self.alpha_flfr, self.fault_index, self.b, self.b_hat
            )
        }

    def chain_outputs(self, measurement) -> dict[str, Any]:
        """The measured chain outputs ``{"position", "velocity"}`` (N-1, axes) [m, m/s]: the chain
        sensors' measurement itself, or formed on board from an (N, 6) relative-state measurement."""
        if isinstance(measurement, Mapping):
            return dict(measurement)
        na = self.n_axes
        return {
            "position": chain_difference(measurement[:, :na]),
            "velocity": chain_difference(measurement[:, 3 : 3 + na]),
        }

    def output(self, t, state, inputs: FlightInputs):
        rd, vd, ad = self.desired(t)
        y = self.chain_outputs(inputs.measurement)
        e = y["position"] - chain_difference(rd)
        e_dot = y["velocity"] - chain_difference(vd)
        # Sec. II
        p = relative_output_law(e, e_dot, chain_difference(ad), self.lambda0, self.lambda1)
        mode = LLFR if inputs.decision is None else inputs.decision
        extra = {}
        if self.fault_estimate == "estimator":
            matrix, k = self.identified_allocation(inputs.estimate, mode)
            extra = {"flfr_spacecraft": (k + 1).astype(jnp.float64)}
        else:
            matrix = state["allocation"][mode]
        u = allocate(matrix, p)  # eq. (3)
        # continuous: the matrices are constant, zero derivative
        nxt = state if self.sampled else {"allocation": jnp.zeros_like(state["allocation"])}
        return u, nxt, {"desired_position": rd, **extra}

    def identified_allocation(self, estimate, mode) -> tuple[jax.Array, jax.Array]:
        """The allocation matrix (eq. (3)) of ``mode`` with the fault the estimator identified: ``b_hat``
        of the isolated channel its identified effectiveness times ``b`` (LLFR, FLFR), FLFR's raised
        weight on the isolated spacecraft (:meth:`output` with ``fault_estimate = "estimator"``; one
        matrix per step, that of the mode in force); and that spacecraft's 0-based index
        (``fault_index`` before an isolation)."""
        na = self.n_axes
        use, eff = isolated_effectiveness(estimate)
        b_hat = jnp.where(use[:, :na], self.b * eff[:, :na], self.b_hat)
        isolated = jnp.asarray(estimate["isolated"])[:, :na] & jnp.asarray(estimate["detected"])
        spacecraft = jnp.any(isolated, axis=1)
        k = jnp.where(jnp.any(spacecraft), jnp.argmax(spacecraft), self.fault_index)
        alpha = jnp.asarray(self.alpha)
        alpha = jnp.where(mode == FLFR, alpha.at[k].set(self.alpha_flfr), alpha)
        b = jnp.where(mode == NOMINAL, jnp.asarray(self.b), b_hat)
        return jax.vmap(lambda col: allocation_matrix(alpha, col), in_axes=1)(b), k

    def signals(self):
        desired = "desired position of the rotating formation"
        sig = (Signal("desired_position", VEC, "m", desired, self.frame),)
        if self.fault_estimate == "estimator":
            isolated = "spacecraft (1-based) whose weight FLFR raises: the one the FDI isolated"
            sig += (Signal("flfr_spacecraft", (), "1", isolated),)
        return sig

    def coords(self):
        return {"pair": [f"{j + 1}-{j + 2}" for j in range(self.count - 1)]}


# ------------------------------------------------------------------------------------------ section
class ChainLlfrSection(StrictModel):
    """Azizi & Khorasani 2009: p_ij = xdd_ij^d - lambda1 e'_ij - lambda0 e_ij on the chain pairs and the
    weighted least-effort allocation u = J_aug(alpha, b_hat)^-1 [p; 0] (eq. (3)) per axis."""

    lambda0: float = Field(gt=0, description="Position gain lambda_0 of p_ij [1/s^2].")
    lambda1: float = Field(gt=0, description="Velocity gain lambda_1 of p_ij [1/s].")
    side: float = Field(
        gt=0, description="Side of the desired regular polygon (a square for 4 spacecraft) [m]."
    )
    omega: float = Field(
        description="Rotation rate of the desired polygon about the frame's third axis [rad/s]."
    )
    alpha: Annotated[float | list[float], positive_values()] = Field(
        1.0, description="LLFR cost weights alpha_i of eq. (3), > 0 [-]."
    )
    alpha_flfr: float | None = Field(
        None,
        gt=0,
        description="FLFR weight of the faulty spacecraft [-] (default: designed by eq. (11) from the "
        "fields below when a hierarchical supervisor may switch to FLFR -- 4 spacecraft, spacecraft "
        "2 faulty -- otherwise its LLFR weight, i.e. FLFR changes nothing).",
    )
    b: Annotated[float | list[float], positive_values()] = Field(
        1.0, description="Nominal actuator gains b_i the law allocates with (every axis) [-]."
    )
    faulty_spacecraft: int | None = builder_input(
        None,
        ge=1,
        description="Spacecraft whose actuator the FDI reports faulty "
        "(1-based; none: no fault known) [-].",
    )
    faulty_axis: Literal["x", "y", "z"] = builder_input(
        "x", description="Axis of the faulty actuator [-]."
    )
    b_hat: float = Field(
        1.0, gt=0, description="FDI estimate of the faulty actuator's gain (LLFR) [-]."
    )
    fault_estimate: Literal["stated", "estimator"] = Field(
        "stated",
        description="Where the fault the allocation uses comes from: 'stated' -- faulty_spacecraft, "
        "faulty_axis and b_hat above (scripted fault information); 'estimator' -- at run time, the "
        "channel the [estimator] isolated and its identified effectiveness (needs an estimator "
        "providing fault-identification, e.g. residual-fdi with identification = 'rls'); FLFR then "
        "raises alpha_flfr on the isolated spacecraft [-].",
    )
    nominal_mass: Masses | None = builder_input(
        None,
        description="Masses the flight side scales the acceleration command with on a force-driven plant "
        "[kg] (the force adapter's nominal_mass; default 100 kg each, a stated nominal value: never the "
        "plant's true masses; not used on an acceleration-driven plant).",
    )
    sampling: Literal["zoh", "continuous"] = builder_input(
        "zoh",
        description="'zoh': computed at t_k and held over the step; 'continuous': every RK stage.",
    )
    b_eps: float = builder_input(
        0.08,
        gt=0,
        description="Known bound B_eps on |b_hat - b| of the FDI estimate [-] (eq. (8)).",
    )
    violation_probability: float = builder_input(
        0.0,
        ge=0,
        lt=1,
        description="pi of eq. (11) for the FLFR weight design, 0 <= pi < 1 (0: deterministic "
        "design (9)) [-].",
    )
    disturbance_bound: float = builder_input(
        2e-5,
        ge=0,
        description="Bound B_ext on the differential disturbance |d_j - d_i| the FLFR design "
        "assumes [m/s^2].",
    )
    design_dt: float = builder_input(
        1e-3, gt=0, description="Step of the simulated H_i of the FLFR design [s]."
    )
    alpha_reference: float = builder_input(
        1.0, gt=0, description="alpha_k at which the FLFR design evaluates A_clp for H_i [-]."
    )


# ------------------------------------------------------------------------------------------ design
def law_gains(
    sec: ChainLlfrSection, n: int, axes: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """The law's numbers for ``n`` spacecraft on ``axes`` axes: weights alpha (N,), nominal gains
    (N, axes), estimated gains b_hat (N, axes) (the FDI estimate on the faulty axis) and the 0-based
    faulty spacecraft k (0 when none is reported).

    Parameters
    ----------
    sec : ChainLlfrSection
        The law's section.
    n : int
        Number of spacecraft.
    axes : int
        Number of axes.

    Returns
    -------
    tuple
        ``(alpha, b, b_hat, k)``.

    Raises
    ------
    ValueError
        A faulty spacecraft or axis the plant does not have (naming the field).

    Examples
    --------
    >>> sec = ChainLlfrSection(lambda0=2.0, lambda1=3.0, side=200.0, omega=0.1,
    ...                        faulty_spacecraft=2, faulty_axis="y", b_hat=0.9)
    >>> alpha, b, b_hat, k = law_gains(sec, 3, 2)
    >>> b_hat.tolist(), k
    ([[1.0, 1.0], [1.0, 0.9], [1.0, 1.0]], 1)
    """
    alpha = per_spacecraft(sec.alpha, n, "controller.alpha")
    b_nom = np.tile(per_spacecraft(sec.b, n, "controller.b")[:, None], (1, axes))
    b_hat = b_nom.copy()
    k = 0
    if sec.faulty_spacecraft is not None:
        k = sec.faulty_spacecraft - 1
        if k >= n:
            raise ValueError(
                f"controller.faulty_spacecraft = {sec.faulty_spacecraft}: the plant has {n} spacecraft"
            )
        if AXES.index(sec.faulty_axis) >= axes:
            raise ValueError(
                f"controller.faulty_axis = {sec.faulty_axis!r}: the plant has {axes} axes"
            )
        b_hat[k, AXES.index(sec.faulty_axis)] = sec.b_hat
    return alpha, b_nom, b_hat, k


def flfr_design(
    sec: ChainLlfrSection, n: int, e_s: float, pis: tuple[float, ...] | None = None
) -> FlfrDesign:
    """Offline FLFR design of eqs. (8)-(11) (:func:`formation_ftc.design.flfr.design_flfr`) of the law
    on ``n`` spacecraft for its faulty spacecraft and axis, mission bound ``e_s`` [m] and violation
    probabilities ``pis`` (default: the law's ``violation_probability``); cached by its inputs. H_i is
    simulated over :data:`DESIGN_HORIZON` (the sup over t needs several rotation periods).

    Parameters
    ----------
    sec : ChainLlfrSection
        The law's section (with a faulty spacecraft).
    n : int
        Number of spacecraft.
    e_s : float
        Mission error bound [m].
    pis : tuple of float, optional
        Violation probabilities of eq. (11) [-].

    Returns
    -------
    FlfrDesign
        The design (H_i, floor, FLFR weights per pi, verdict).

    Raises
    ------
    ValueError
        The section states no faulty spacecraft.

    Examples
    --------
    >>> flfr_design(ChainLlfrSection(lambda0=2.0, lambda1=3.0, side=200.0, omega=0.1), 4, 0.03)
    Traceback (most recent call last):
    ...
    ValueError: the FLFR design needs controller.faulty_spacecraft
    """
    if sec.faulty_spacecraft is None:
        raise ValueError("the FLFR design needs controller.faulty_spacecraft")
    pis = (sec.violation_probability,) if pis is None else pis
    return _design_cached(sec.model_dump_json(), n, float(e_s), tuple(float(p) for p in pis))


@functools.lru_cache(maxsize=32)
def _design_cached(section: str, n: int, e_s: float, pis: tuple[float, ...]) -> FlfrDesign:
    """:func:`flfr_design` of the section given as its JSON text (a hashable cache key)."""
    from formation_ftc.core.polygon_formation import relative_acceleration_fn
    from formation_ftc.design.flfr import design_flfr

    sec = ChainLlfrSection.model_validate_json(section)
    axis = AXES.index(sec.faulty_axis)
    alpha, _, b_hat, k = law_gains(sec, n, axis + 1)
    w_fn = relative_acceleration_fn(n, sec.side, sec.omega, axis)
    return design_flfr(
        alpha, b_hat[:, axis], k, sec.b_eps, sec.lambda0, sec.lambda1, e_s, pis, w_fn,
        DESIGN_HORIZON, sec.design_dt, sec.disturbance_bound, sec.alpha_reference,
    )  # fmt: skip


def _alpha_flfr(sec: ChainLlfrSection, ctx: BuildContext, alpha: np.ndarray, k: int) -> float:
    """The FLFR weight: stated, or designed by eq. (11) for the mission bound ``e_s`` of a supervisor
    that may switch to FLFR (its ``flfr``; never below the LLFR weight), or the LLFR weight where no
    supervisor may switch to FLFR."""
    if sec.alpha_flfr is not None:
        return float(sec.alpha_flfr)
    sup = ctx.section("supervisor")
    e_s = getattr(sup, "e_s", None)
    if e_s is None or not getattr(sup, "flfr", False) or sec.faulty_spacecraft is None:
        return float(alpha[k])
    if ctx.count != 4 or k != 1:
        raise ValueError(
            "controller.alpha_flfr: its design by eq. (11) (reduced model (7)) is implemented for 4 "
            "spacecraft with spacecraft 2 faulty; give controller.alpha_flfr"
        )
    des = flfr_design(sec, ctx.count, e_s)
    if des.verdict == "infeasible":
        raise ValueError(f"controller.alpha_flfr: {des.message}")
    a = des.alpha[float(sec.violation_probability)]
    assert a is not None  # None only when infeasible (raised above)
    return max(float(a), float(alpha[k]))  # never lower the weight (LLFR already suffices)


# ------------------------------------------------------------------------------------------ builder
def _build(sec: ChainLlfrSection, ctx: BuildContext) -> Controller:
    """The controller of a validated ``[controller] type = "azizi2009-llfr"`` section: the law, times
    the nominal masses on a force-driven plant."""
    from formation_ftc.components.controllers._acceleration_to_force import force_from_acceleration
    from formation_ftc.components.evaluations.chain_errors import ChainTrackingError
    from formation_ftc.design.allocation import validate_allocation_inputs

    n = ctx.count
    layout, axes = chain_layout(ctx)
    alpha, b_nom, b_hat, k = law_gains(sec, n, axes)
    for a in range(axes):
        validate_allocation_inputs(alpha, b_hat[:, a], "controller.alpha", "controller.b_hat")
    law = ChainLlfrController(
        **section_floats(sec, "lambda0", "lambda1", "side", "omega"),
        alpha=as_float(alpha),
        alpha_flfr=as_float(_alpha_flfr(sec, ctx, alpha, k)),
        b=as_float(b_nom),
        b_hat=as_float(b_hat),
        fault_index=k,
        fault_estimate=sec.fault_estimate,
        is_sampled=sec.sampling == "zoh",
        frame="LVLH" if layout == "q" else "inertial",
    )
    if any(s.name == "position" for s in ctx.plant.signals()):
        # the true chain errors; a [[evaluations]] chain-errors of the scenario replaces them
        ctx.evaluations.append(ChainTrackingError())
    if ctx.plant.quantity != "force":  # an acceleration-driven plant flies the law itself
        if sec.nominal_mass is not None and ctx.plant.quantity == "acceleration":
            raise ValueError(
                "controller.nominal_mass: the plant is driven by accelerations, there is no mass to "
                "scale with"
            )
        return law  # (validation refuses a law of accelerations on any other plant)
    mass = NOMINAL_MASS if sec.nominal_mass is None else sec.nominal_mass  # never the plant's
    return force_from_acceleration(
        law, as_float(per_spacecraft(mass, n, "controller.nominal_mass"))
    )


register(
    "controller",
    "azizi2009-llfr",
    ChainLlfrSection,
    _build,
    "Azizi2009 relative-output chain law with LLFR allocation (deep-space double-integrator "
    "model; force plants: times the nominal masses)",
)
