"""Controller ``lqr``: LQR formation keeping on the Clohessy-Wiltshire model, the non-fault-tolerant
baseline a fault-tolerant law should beat.

The gain is designed before the run on the CW model of the design orbit (its radius ``semi_major_axis``
and ``mu``; default the ``[reference]`` orbit's, never the plant's), weights by Bryson's rule
(:func:`formation_ftc.design.lqr.cw_lqr`); the feed-forward makes the desired state an equilibrium of
that model. The law reads only the measured relative state
(:class:`~formation_ftc.sim.components.FlightInputs`): no communication, no fault estimate, no
adaptation; its on-board masses are stated (``nominal_mass``, default 100 kg).
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

import jax.numpy as jnp
from pydantic import Field

from formation_ftc.components._flight_defaults import NOMINAL_MASS
from formation_ftc.components._registry import BuildContext, builder_input, per_spacecraft, register
from formation_ftc.components._sections import Masses, Vec3, Vec3Expr, positive_values
from formation_ftc.components.controllers._desired_position import DesiredPositionLaw
from formation_ftc.config.base import StrictModel
from formation_ftc.core.constants import MU_EARTH
from formation_ftc.core.dynamics.cw import cw_rhs
from formation_ftc.sim.components import Controller, FlightInputs, component
from formation_ftc.sim.contract import as_float

__all__ = ["LqrFormationController", "LqrSection"]


@component
class LqrFormationController(DesiredPositionLaw):
    """LQR state feedback with the feed-forward that makes the desired state a CW equilibrium [N]::

        u_i = m_i ( -K (q_i - q_i^d) - (A q_i^d)[3:] + a_i^d )        (1)

    q_i = [p_i, v_i] is the measured LVLH state [m, m/s], q_i^d = [p_i^d(t), v_i^d(t)] the desired one
    and a_i^d(t) its acceleration (expressions as in
    :class:`~formation_ftc.components.controllers._desired_position.DesiredPositionLaw`); A is the CW matrix
    of the on-board mean motion. On the CW model, (1) gives the error dynamics
    ``e_dot = (A - B K) e`` with ``e = q - q^d`` (the feed-forward cancels ``A q^d - q_dot^d``).

    ``gain`` K (3, 6) [1/s^2 | 1/s] is designed before the run (e.g. by
    :func:`formation_ftc.design.lqr.cw_lqr`); a campaign that varies ``mean_motion`` does not redesign it.
    ``nominal_mass`` (N,) is the on-board mass m_i [kg]; ``mean_motion`` n [rad/s] of the on-board model.
    """

    gain: Any = None  # (3, 6) K [1/s^2 | 1/s]
    nominal_mass: Any = 1.0  # (N,) on-board masses [kg]
    mean_motion: Any = 0.0  # on-board n [rad/s]

    def output(self, t, state, inputs: FlightInputs):
        y, d = inputs.measurement, inputs.exogenous
        qd = jnp.concatenate([d["p"], d["v"]], axis=-1)  # (N, 6)
        # (A q^d)[3:]: the CW accelerations of the desired state with no input
        drift = cw_rhs(t, qd, jnp.zeros_like(d["a"]), self.mean_motion)[:, 3:]
        accel = -(y - qd) @ jnp.transpose(self.gain) - drift + d["a"]  # eq. (1) / m_i
        return self.nominal_mass[:, None] * accel, None, {}


#: a limit of Bryson's rule: one number or one per axis, each finite and > 0
_Limit = Annotated[float | Vec3, positive_values()]


class LqrSection(StrictModel):
    """LQR on the CW model: weights by Bryson's rule, Q = diag(1/e_max^2), R = diag(1/a_max^2)."""

    max_position_error: _Limit = builder_input(
        description="Bryson's rule: largest acceptable position error [m], one number or one per LVLH axis; > 0."
    )
    max_velocity_error: _Limit = builder_input(
        description="Bryson's rule: largest acceptable velocity error [m/s], one number or one per axis; > 0."
    )
    max_acceleration: _Limit = builder_input(
        description="Bryson's rule: largest acceptable commanded acceleration [m/s^2], one number or one per axis; > 0."
    )
    semi_major_axis: float | None = builder_input(
        None,
        gt=0,
        description="Radius of the circular orbit the gain is designed on [m] (default: the [reference] "
        "orbit's semi_major_axis, known on board; required without a [reference]; never the "
        "plant's).",
    )
    mu: float | None = builder_input(
        None,
        gt=0,
        description="Gravitational parameter of the on-board model [m^3/s^2] (default: the "
        "[reference] orbit's, else Earth's 3.986004418e14; never the plant's).",
    )
    nominal_mass: Masses = Field(
        NOMINAL_MASS,
        description="Nominal on-board mass per spacecraft [kg], one or per spacecraft, > 0 (default "
        "100 kg, a stated nominal value: never the plant's true masses).",
    )
    desired_position: Vec3Expr = Field(
        ("0", "0", "0"), description="Desired LVLH position, expressions in t [s], i [m]."
    )
    mode: Literal["continuous", "sampled"] = builder_input(
        "continuous", description="Every RK stage or held over the step."
    )
    fault_estimate: Literal["none", "estimator"] = builder_input(
        "none",
        description="'estimator': the command is reallocated with the [estimator]'s fault "
        "identification (divided by the identified effectiveness of the isolated channel, up to "
        "force_limit; needs residual-fdi with identification = 'rls'); 'none': the plain LQR [-].",
    )
    force_limit: float = builder_input(
        math.inf,
        gt=0,
        description="Rated thrust per axis the reallocation respects [N] (flight knowledge; inf: none).",
    )


def _from_reference(ctx: BuildContext, name: str) -> float | None:
    """A field of the [reference] orbit (known on board), or None; the plant's truth is never read."""
    value = getattr(ctx.section("reference"), name, None)
    return None if value is None else float(value)


def _build(sec: LqrSection, ctx: BuildContext) -> Controller:
    """The controller of a validated ``[controller] type = "lqr"`` section."""
    from formation_ftc.design.lqr import cw_lqr

    a = sec.semi_major_axis
    if a is None:
        a = _from_reference(ctx, "semi_major_axis")
    if a is None:
        raise ValueError(
            "controller.semi_major_axis: required (the loop has no [reference] orbit to take the design "
            "orbit from; the plant's orbit is truth the law does not read)"
        )
    mu = sec.mu if sec.mu is not None else _from_reference(ctx, "mu") or MU_EARTH
    n = math.sqrt(mu / a**3)  # mean motion of the circular design orbit [rad/s]
    design = cw_lqr(n, sec.max_position_error, sec.max_velocity_error, sec.max_acceleration)
    law = LqrFormationController(
        count=ctx.count,
        gain=as_float(design.K),
        mean_motion=as_float(n),
        nominal_mass=as_float(
            per_spacecraft(sec.nominal_mass, ctx.count, "controller.nominal_mass")
        ),
        desired_position=sec.desired_position,
        is_sampled=sec.mode == "sampled",
    )
    if sec.fault_estimate == "estimator":
        from formation_ftc.components.controllers._reconfiguring import reconfigured

        return reconfigured(law, sec.force_limit)
    return law


register(
    "controller",
    "lqr",
    LqrSection,
    _build,
    "LQR baseline designed on Clohessy-Wiltshire (Bryson weights), no fault tolerance",
)
