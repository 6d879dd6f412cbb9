"""Plant ``euler-angle-attitude``: rigid-body attitudes in Euler angles, driven by generalised torques
(an Euler-Lagrange plant; Mehrabian (1), (27)-(28)).

State of every spacecraft: Euler angles ``q = [theta, phi, psi]`` (pitch, roll, yaw) [rad] and body
rates ``w`` [rad/s]; the applied input is the generalised torque ``u`` [N m] conjugate to ``q`` (body
torque ``R_bar(q)^T u``), see :mod:`formation_ftc.core.dynamics.euler_lagrange`::

    q_dot = R_bar(q) w,   J w_dot = -w x J w + R_bar(q)^T (u + d_k)           (Mehrabian (1), (27)-(28))

with the true inertia ``J = J^ diag(1 + delta)``, ``delta ~ U[-spread, spread]^3`` per spacecraft, and an
input disturbance ``d_k ~ N(0, std^2 I)`` per spacecraft and channel, drawn for every step and held over
it. The random numbers come from the plant's own ``seed`` leaf (``run_key(seed)`` split into initial
attitudes, inertia, disturbance and one stream left to the FDI): a campaign varies the seed as a leaf,
a run is deterministic in it, and per-step draws use ``fold_in(key, k)`` (independent of batching).

The Euler-angle law (``networked-el-hinf``) reads this state directly (no ``[sensors]``), and the
``euler-torque-allocation`` actuator applies its additive faults to the generalised torque without a
mapping: the plant provides the capabilities ``euler-angle-attitude-state``,
``euler-angle-measurement`` and ``generalised-torque-actuation``.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from pydantic import Field, model_validator

from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.components._sections import Inertia, Vec3, check_rows
from formation_ftc.config.base import StrictModel
from formation_ftc.core.constants import SINGULAR_PITCH_LIMIT_RAD, check_away_from_singularity
from formation_ftc.core.disturbances import run_key, step_key
from formation_ftc.core.dynamics.euler_lagrange import (
    body_rates_from_euler_rates,
    euler_rates_from_body_rates,
    rigid_body_rhs,
)
from formation_ftc.sim.components import Plant, Signal, StepContext, TruthInputs, component
from formation_ftc.sim.contract import VEC, as_float

__all__ = ["EulerAngleAttitudePlant", "EulerAnglePlantSection", "seed_streams", "AXES"]

#: names of the Euler angles, in the order of the state's last axis
AXES = ("pitch", "roll", "yaw")


def seed_streams(seed) -> tuple[jax.Array, jax.Array, jax.Array, jax.Array]:
    """The four random streams of a run: (initial attitudes, inertia, disturbance, FDI noise).

    Parameters
    ----------
    seed : int or array_like
        The run's seed (uint32) [-].

    Returns
    -------
    tuple of jax.Array
        Four independent root keys.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.plants.euler_angle_attitude import seed_streams
    >>> keys = seed_streams(42)
    >>> len(keys), bool(np.array_equal(keys[0], seed_streams(42)[0]))
    (4, True)
    >>> bool(np.array_equal(keys[0], keys[1]))
    False
    """
    k_q0, k_J, k_d, k_fdi = jax.random.split(run_key(seed), 4)
    return k_q0, k_J, k_d, k_fdi


@component
class EulerAngleAttitudePlant(Plant):
    """m rigid spacecraft in Euler angles (see the module docstring).

    Leaves: ``seed`` (uint32), ``random_initial_attitude`` (1: draw the initial angles from
    ``U[q0_range]``, 0: use ``q0_fixed``), ``q0_range`` (2,) [rad], ``q0_fixed`` (m, 3) [rad], ``qdot0``
    (m, 3) initial Euler-angle rates [rad/s], ``inertia`` (m, 3) principal inertias J^ about which the
    true ones are drawn [kg m^2], ``inertia_uncertainty`` [-], ``disturbance_std`` [N m]. The held
    disturbance is drawn for the loop's step index (its step context), so it has no step of its own.
    ``J``, ``J_inv`` are filled by :meth:`prepare` (once per run).
    """

    quantity = "torque"
    holds_exogenous = True  # the disturbance d_k is drawn at t_k and held over the step

    seed: Any
    random_initial_attitude: Any
    q0_range: Any
    q0_fixed: Any
    qdot0: Any
    inertia: Any
    inertia_uncertainty: Any
    disturbance_std: Any
    # set by prepare (empty until then: no leaves): (m, 3, 3) true inertia [kg m^2], its inverse and
    # the root key of the disturbance stream
    J: Any = ()
    J_inv: Any = ()
    noise_key: Any = ()

    @property
    def count(self) -> int:
        return int(np.shape(self.q0_fixed)[0])

    def prepare(self, dt):
        """Draw the true inertia J = J^ diag(1 + delta), delta ~ U[-spread, spread]^3, and derive the
        disturbance key (once per run)."""
        _, k_J, k_d, _ = seed_streams(self.seed)
        delta = self.inertia_uncertainty * jax.random.uniform(
            k_J, (self.count, 3), dtype=jnp.float64, minval=-1.0, maxval=1.0
        )
        J = jax.vmap(jnp.diag)(self.inertia * (1.0 + delta))
        return dataclasses.replace(self, J=J, J_inv=jnp.linalg.inv(J), noise_key=k_d)

    def initial_state(self):
        k_q0, _, _, _ = seed_streams(self.seed)
        lo, hi = self.q0_range[0], self.q0_range[1]
        q_rand = jax.random.uniform(k_q0, (self.count, 3), dtype=jnp.float64, minval=lo, maxval=hi)
        q0 = jnp.where(self.random_initial_attitude > 0.5, q_rand, self.q0_fixed)
        return {"q": q0, "w": body_rates_from_euler_rates(q0, self.qdot0)}

    def angular_rate(self, x):
        return x["w"]

    def provides(self) -> frozenset[str]:
        return frozenset(
            {
                "euler-angle-attitude-state",
                "euler-angle-measurement",
                "generalised-torque-actuation",
            }
        )

    def euler_pitch(self, x):
        return x["q"][..., 0]  # theta, the middle angle of the 3-2-1 sequence (AXES[0])

    def held_exogenous(self, step: StepContext):
        """d_k ~ N(0, std^2 I) for the loop's step k, held over it [N m]."""
        # the disturbance stream's root key (prepare computes it once per run)
        k_d = seed_streams(self.seed)[2] if isinstance(self.noise_key, tuple) else self.noise_key
        z = jax.random.normal(step_key(k_d, step.k), (self.count, 3), dtype=jnp.float64)
        return {"d": self.disturbance_std * z}

    def derivative(self, t, x, inputs: TruthInputs):
        # (1), (27): J w_dot = -w x J w + R_bar^T (u + d)
        q_dot, w_dot = rigid_body_rhs(
            x["q"], x["w"], inputs.force + inputs.exogenous["d"], self.J, self.J_inv
        )
        return {"q": q_dot, "w": w_dot}

    def signals(self):
        return (
            Signal(
                "attitude", VEC, "rad", "Euler angles [theta, phi, psi]", "body to inertial Z-Y-X"
            ),
            Signal("attitude_rate", VEC, "rad s-1", "Euler-angle rates", "body to inertial Z-Y-X"),
            Signal("disturbance", VEC, "N m", "input disturbance d, held over the step"),
        )

    def coords(self):
        return {"axis": list(AXES)}

    def outputs(self, t, x, inputs: TruthInputs):
        return {
            "attitude": x["q"],
            "attitude_rate": euler_rates_from_body_rates(x["q"], x["w"]),
            "disturbance": inputs.exogenous["d"],
        }


_PITCH_LIMIT_DEG = float(np.rad2deg(SINGULAR_PITCH_LIMIT_RAD))


class EulerAnglePlantSection(StrictModel):
    """m rigid bodies in 3-2-1 Euler angles driven by generalised torques (Mehrabian (1), (27)-(28)):
    true inertias drawn about ``inertia``, random or given initial angles, a Gaussian input disturbance
    held over each step; every draw from the run seed. Defaults: the paper's data and our choices
    (E003-10)."""

    count: int = builder_input(8, ge=1, le=64, description="Number m of spacecraft [-].")
    inertia: Inertia = Field(
        (20.0, 18.0, 15.0),
        description="Principal inertia diag(...) about which every spacecraft's true inertia is drawn "
        "[kg m^2], each > 0 (default 20, 18, 15 kg m^2, our choice E003-10; an attitude law's "
        "model is stated in its own section).",
    )
    inertia_uncertainty: float = Field(
        0.1,
        ge=0.0,
        lt=1.0,
        description="True J = diag(inertia) diag(1 + delta), delta ~ U[-u, u]^3 per spacecraft, drawn "
        "from the run seed [-] (paper: +-10 %).",
    )
    random_initial_attitude: bool = Field(
        True,
        description="Draw every initial Euler angle from U[initial_attitude_range_deg] with the run seed "
        "(inside the run, so a campaign varies it through the seed); false: initial_attitude_deg.",
    )
    initial_attitude_range_deg: tuple[float, float] = builder_input(
        (0.0, 60.0), description="Range of the random initial Euler angles [deg] (paper: 0..60)."
    )
    initial_attitude_deg: list[Vec3] | None = builder_input(
        None,
        description="Initial [theta (pitch), phi (roll), psi (yaw)] per spacecraft [deg] (used when "
        "random_initial_attitude = false).",
    )
    initial_rate_deg_s: list[Vec3] | None = builder_input(
        None,
        description="Initial Euler-angle rates per spacecraft [deg/s] (default 0, our choice).",
    )
    disturbance_variance: float = builder_input(
        0.001,
        ge=0.0,
        description="Variance of the Gaussian input disturbance d_j, i.i.d. per spacecraft and channel, "
        "held over each step [(N m)^2] (paper: 0.001).",
    )

    @model_validator(mode="after")
    def _check(self):
        lo, hi = self.initial_attitude_range_deg
        if not lo <= hi:
            raise ValueError(
                f"initial_attitude_range_deg = [{lo}, {hi}]: lower bound must be <= upper bound"
            )
        if self.random_initial_attitude and max(abs(lo), abs(hi)) >= _PITCH_LIMIT_DEG:
            raise ValueError(
                f"initial_attitude_range_deg = [{lo}, {hi}] deg can draw a pitch at or beyond "
                f"+-{_PITCH_LIMIT_DEG:.0f} deg: the Euler-angle EL model is singular at theta = +-90 deg "
                "(R_bar has 1/cos(theta), E003-08); use a range inside "
                f"(-{_PITCH_LIMIT_DEG:.0f}, {_PITCH_LIMIT_DEG:.0f}) deg"
            )
        if not self.random_initial_attitude:
            if self.initial_attitude_deg is None:
                raise ValueError(
                    "initial_attitude_deg is required when random_initial_attitude = false"
                )
            check_away_from_singularity(
                np.deg2rad(np.asarray(self.initial_attitude_deg, dtype=float)),
                field="initial_attitude_deg",
            )
        check_rows(self, ["initial_attitude_deg", "initial_rate_deg_s"], self.count)
        return self


def _build(sec: EulerAnglePlantSection, ctx: BuildContext) -> EulerAngleAttitudePlant:
    """The plant of a validated ``[plant] type = "euler-angle-attitude"`` section."""
    m = sec.count

    def rows(v):
        return np.zeros((m, 3)) if v is None else np.deg2rad(np.asarray(v, dtype=float))

    return EulerAngleAttitudePlant(
        seed=np.asarray(ctx.scenario.simulation.seed, dtype=np.uint32),
        random_initial_attitude=as_float(1.0 if sec.random_initial_attitude else 0.0),
        q0_range=as_float(np.deg2rad(sec.initial_attitude_range_deg)),
        q0_fixed=as_float(rows(sec.initial_attitude_deg)),
        qdot0=as_float(rows(sec.initial_rate_deg_s)),
        inertia=as_float(np.tile(np.asarray(sec.inertia), (m, 1))),
        inertia_uncertainty=as_float(sec.inertia_uncertainty),
        disturbance_std=as_float(np.sqrt(sec.disturbance_variance)),
    )


register(
    "plant",
    "euler-angle-attitude",
    EulerAnglePlantSection,
    _build,
    "rigid-body attitudes in 3-2-1 Euler angles driven by generalised torques, drawn inertias, held "
    "input noise (Mehrabian (1), (27)-(28))",
)
