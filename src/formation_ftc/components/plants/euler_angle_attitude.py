"""Rigid-body attitudes in Euler angles, driven by generalised torques (an Euler-Lagrange plant).

State of every spacecraft: Euler angles ``q = [theta, phi, psi]`` (pitch, roll, yaw) [rad] and body
rates ``w`` [rad/s]; the applied input is the generalised torque ``u`` [N m] conjugate to ``q`` (body
torque ``R_bar(q)^T u``), see :mod:`formation_ftc.core.dynamics.euler_lagrange`::

    q_dot = R_bar(q) w,   J w_dot = -w x J w + R_bar(q)^T (u + d_k)           (Mehrabian (1), (27)-(28))

with the true inertia ``J = J^ diag(1 + delta)``, ``delta ~ U[-spread, spread]^3`` per spacecraft, and an
input disturbance ``d_k ~ N(0, std^2 I)`` per spacecraft and channel, drawn for every step and held over
it. The random numbers come from the plant's own ``seed`` leaf (``run_key(seed)`` split into initial
attitudes, inertia, disturbance and one stream left to the FDI): a campaign varies the seed as a leaf,
a run is deterministic in it, and per-step draws use ``fold_in(key, k)`` (independent of batching).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from formation_ftc.core.disturbances import run_key, step_key
from formation_ftc.core.dynamics.euler_lagrange import (
    body_rates_from_euler_rates,
    euler_rates_from_body_rates,
    rigid_body_rhs,
)
from formation_ftc.sim.components import Plant, Signal, TruthInputs, component, static

__all__ = ["EulerAngleAttitudePlant", "seed_streams"]

VEC = ("spacecraft", "axis")
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

    Leaves: ``seed`` (uint32), ``random_initial`` (1: draw the initial angles from ``U[q0_range]``, 0:
    use ``q0_fixed``), ``q0_range`` (2,) [rad], ``q0_fixed`` (m, 3) [rad], ``qdot0`` (m, 3) initial
    Euler-angle rates [rad/s], ``J_nominal`` (m, 3) principal inertias [kg m^2], ``inertia_spread`` [-],
    ``disturbance_std`` [N m]. Static: ``step`` -- the sampling period of the held disturbance [s] (the
    loop's step). ``J``, ``J_inv`` are filled by :meth:`prepare` (once per run).
    """

    quantity = "torque"
    holds_exogenous = True  # the disturbance d_k is drawn at t_k and held over the step

    seed: Any
    random_initial: Any
    q0_range: Any
    q0_fixed: Any
    qdot0: Any
    J_nominal: Any
    inertia_spread: Any
    disturbance_std: Any
    step: float = static()
    t0: float = static(default=0.0)
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
        delta = self.inertia_spread * jax.random.uniform(
            k_J, (self.count, 3), dtype=jnp.float64, minval=-1.0, maxval=1.0
        )
        J = jax.vmap(jnp.diag)(self.J_nominal * (1.0 + delta))
        return dataclasses.replace(self, J=J, J_inv=jnp.linalg.inv(J), noise_key=k_d)

    def initial_state(self):
        k_q0, _, _, _ = seed_streams(self.seed)
        lo, hi = self.q0_range[0], self.q0_range[1]
        q_rand = jax.random.uniform(k_q0, (self.count, 3), dtype=jnp.float64, minval=lo, maxval=hi)
        q0 = jnp.where(self.random_initial > 0.5, q_rand, self.q0_fixed)
        return {"q": q0, "w": body_rates_from_euler_rates(q0, self.qdot0)}

    def angular_rate(self, x):
        return x["w"]

    def euler_pitch(self, x):
        return x["q"][..., 0]  # theta, the middle angle of the 3-2-1 sequence (AXES[0])

    def exogenous(self, t):
        """d_k ~ N(0, std^2 I) for the step starting at t = t_k, held over it [N m]."""
        # the disturbance stream's root key (prepare computes it once per run)
        k_d = seed_streams(self.seed)[2] if isinstance(self.noise_key, tuple) else self.noise_key
        k = jnp.round((t - self.t0) / self.step).astype(jnp.int64)
        return {
            "d": self.disturbance_std
            * jax.random.normal(step_key(k_d, k), (self.count, 3), dtype=jnp.float64)
        }

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
