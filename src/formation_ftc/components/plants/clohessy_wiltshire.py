"""Plant ``clohessy-wiltshire``: N point-mass deputies on the linear Clohessy-Wiltshire relative motion
about a circular reference orbit, and the conditions of a linear state feedback on it (closed-loop
stability, RK4 step)."""

from __future__ import annotations

import math
from typing import Any

import jax.numpy as jnp
import numpy as np
from pydantic import Field, model_validator

from formation_ftc.components._registry import BuildContext, builder_input, register
from formation_ftc.components._sections import section_floats
from formation_ftc.components.expressions import vector_expression
from formation_ftc.components.plants._relative_state import (
    PointMassSection,
    PointMassUsage,
    RelativeStatePlant,
)
from formation_ftc.core.constants import MU_EARTH
from formation_ftc.core.disturbances import gaussian_noise
from formation_ftc.core.dynamics.cw import cw_matrices, cw_rhs
from formation_ftc.core.rounding import eigenvalue_margin
from formation_ftc.sim.components import Signal, TruthInputs, component, static
from formation_ftc.sim.contract import VEC, Condition, as_float

__all__ = ["ClohessyWiltshirePlant", "CwPlantSection", "rk4_amplification"]


def rk4_amplification(z: np.ndarray) -> np.ndarray:
    """|R(z)| of classical RK4, the amplification of one step of a linear mode.

    Parameters
    ----------
    z : array_like
        Eigenvalue times step, lambda dt [-] (complex).

    Returns
    -------
    numpy.ndarray
        |R(z)| = |1 + z + z^2/2 + z^3/6 + z^4/24| [-]: the mode is integrated stably when <= 1.

    Examples
    --------
    >>> round(float(rk4_amplification(-1.0)), 12)  # |1 - 1 + 1/2 - 1/6 + 1/24|
    0.375
    """
    z = np.asarray(z, dtype=complex)
    return np.abs(1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24)


@component
class ClohessyWiltshirePlant(PointMassUsage, RelativeStatePlant):
    """N point-mass deputies on linear Clohessy-Wiltshire dynamics about a circular reference orbit.

    State ``{"q": (N, 6)}``, q = [x, y, z, vx, vy, vz] in LVLH (x radial, y along-track, z orbit normal)
    [m, m/s]; ``q_dot = A(n) q + B (F + d(t) + w) / m`` with the applied force F [N], the disturbance
    expressions d(t) [N] and a per-step Gaussian process-noise force w [N] (held over the step).
    """

    mean_motion: Any  # n [rad/s]
    mass: Any  # (N,) [kg]
    initial_state_lvlh: Any  # (N, 6) [m, m/s]
    process_noise_std: Any = 0.0  # [N]
    #: expressions in t, i [N]
    disturbance_force: tuple[str, str, str] = static(default=("0", "0", "0"))

    def exogenous(self, t):
        return {"d": vector_expression(self.disturbance_force, "disturbance.force", t, self.count)}

    def process_noise(self, key):
        return gaussian_noise(key, (self.count, 3), self.process_noise_std)

    def derivative(self, t, x, inputs: TruthInputs):
        f = inputs.force + inputs.exogenous["d"] + inputs.process_noise
        return {"q": cw_rhs(t, x["q"], f / self.mass[:, None], self.mean_motion)}

    def usage_rates(self, t, x, command):
        # PointMassUsage's rates with jnp's norm and sum, not norm3/sq_norm3: the other reduction order
        # moves compose-li2020-on-cw's metrics in the last bits, and the reproduction numbers stay
        return {
            "delta_v": jnp.linalg.norm(command, axis=-1) / self.mass,
            "control_effort": jnp.sum(command**2, axis=-1),
        }

    def signals(self):
        return (
            Signal("position", VEC, "m", "position relative to the reference", "LVLH"),
            Signal("velocity", VEC, "m s-1", "velocity relative to the reference", "LVLH"),
            Signal("delta_v", ("spacecraft",), "m s-1", "commanded delta-v, integral of |u|/m"),
            Signal("control_effort", ("spacecraft",), "N2 s", "integral of |u|^2"),
        )

    def outputs(self, t, x, inputs):
        return {"position": x["q"][:, :3], "velocity": x["q"][:, 3:]}

    def feedback_conditions(self, gain: np.ndarray | None, dt: float) -> list[Condition]:
        """Conditions of the state feedback ``F_i = -gain q_i`` [N] on this (linear) model, true masses
        m_i [kg]: the closed-loop eigenvalues of A - B gain / m_i must have negative real parts, and
        the RK4 step must integrate every closed-loop mode stably (|R(lambda dt)| <= 1). Both are exact
        for the linear model up to the eigenvalues' rounding margin
        (:func:`formation_ftc.core.rounding.eigenvalue_margin`): a real part within the margin of 0
        does not count as stable.

        Parameters
        ----------
        gain : numpy.ndarray or None
            (3, 6) state-feedback gain [N/m | N s/m]; None: no control (the modes of A alone).
        dt : float
            The loop's step [s].

        Returns
        -------
        list of Condition
            One stability condition per spacecraft (with a gain) and the RK4 step condition.
        """
        A, B = cw_matrices(self.mean_motion)
        loops = [A]  # no control: the modes of A alone
        if gain is not None:
            # a subnormal mass: FloatingPointError, not inf gains
            with np.errstate(over="raise"):
                gains = [gain / m for m in np.asarray(self.mass)]
            loops = [A - B @ K for K in gains]  # closed loops of the linear CW model
        out, eigs, margins = [], [], []
        for i, M in enumerate(loops):
            ev = np.linalg.eigvals(M)
            tol = eigenvalue_margin(M)
            eigs.append(ev)
            margins.append(np.full(ev.shape, tol))
            if gain is not None:
                out.append(
                    Condition(
                        name=f"closed-loop stable, spacecraft {i + 1}",
                        reference="linear CW + PD",
                        value=f"max Re(eig) = {ev.real.max():.4g} 1/s",
                        requirement=f"< -{tol:.2g} (rounding margin)",
                        holds=bool(ev.real.max() < -tol),
                        required=True,
                        basis="exact",
                        detail="exact: eigenvalues of the 6 x 6 closed-loop matrix (LAPACK, float64), "
                        f"rounding margin {tol:.2g} 1/s (Bauer-Fike: kappa(V) 10 n eps ||A - BK||)",
                    )
                )
        ev_all = np.concatenate(eigs)
        tol_all = np.concatenate(margins)
        amp = rk4_amplification(ev_all * dt)
        worst = int(np.argmax(amp))
        stable_modes = ev_all.real < -tol_all
        # a mode that is stable in continuous time must stay damped by the RK4 step (|R| <= 1)
        ok = bool(np.all(amp[stable_modes] <= 1.0)) if stable_modes.any() else True
        out.append(
            Condition(
                name="RK4 step vs closed-loop modes",
                reference="RK4 stability region",
                value=f"dt max|lambda| = {dt * np.abs(ev_all).max():.3g}, max |R(lambda dt)| = "
                f"{amp.max():.4g} (at lambda = {ev_all[worst]:.3g} 1/s)",
                requirement="|R(lambda dt)| <= 1 for every stable mode",
                holds=ok,
                required=True,
                basis="exact",
                detail="exact for the linear closed loop: RK4 amplification factor R(z) = 1 + z + z^2/2 "
                "+ z^3/6 + z^4/24 evaluated at every closed-loop eigenvalue times dt (LAPACK "
                "eigenvalues; modes within the rounding margin of the imaginary axis are not counted "
                "as stable)",
            )
        )
        return out


class CwPlantSection(PointMassSection):
    """Point masses on the linear CW model of a circular orbit of radius ``semi_major_axis`` (the builder
    turns it and ``mu`` into the plant's ``mean_motion``)."""

    semi_major_axis: float = builder_input(
        gt=0, description="Radius of the circular reference orbit [m]."
    )
    mu: float = builder_input(MU_EARTH, gt=0, description="Gravitational parameter [m^3/s^2].")
    process_noise_std: float = Field(0.0, ge=0, description="Std of a per-step Gaussian force [N].")

    @model_validator(mode="after")
    def _finite_mean_motion(self):
        try:
            n = self.mean_motion
        except ArithmeticError:  # a^3 overflows or underflows float64
            n = math.nan
        if not (n > 0 and math.isfinite(n)):
            raise ValueError(
                f"semi_major_axis = {self.semi_major_axis:g} m: the mean motion sqrt(mu / a^3) "
                "[rad/s] is not a finite float64 > 0"
            )
        return self

    @property
    def mean_motion(self) -> float:
        """n = sqrt(mu / a^3) [rad/s]."""
        return math.sqrt(self.mu / self.semi_major_axis**3)


def _build(sec: CwPlantSection, ctx: BuildContext) -> ClohessyWiltshirePlant:
    """The plant of a validated ``[plant] type = "clohessy-wiltshire"`` section."""
    return ClohessyWiltshirePlant(
        **section_floats(sec, "mean_motion", "mass", "process_noise_std"),
        initial_state_lvlh=as_float(sec.q0()),
        disturbance_force=sec.disturbance_force,
    )


register(
    "plant",
    "clohessy-wiltshire",
    CwPlantSection,
    _build,
    "linear Clohessy-Wiltshire relative motion about a circular orbit (point masses)",
)
