"""Inertial truth of a formation: every spacecraft and a virtual chief in ECI with J2, drag and SRP."""

from __future__ import annotations

import dataclasses
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from formation_ftc.components.expressions import vector_expression
from formation_ftc.core.dynamics.orbital_truth import (
    EXPONENTIAL_ATMOSPHERE,
    J2_EARTH,
    MU_EARTH,
    OMEGA_EARTH,
    R_EARTH,
    SOLAR_PRESSURE,
    eci_to_lvlh,
    elements_to_eci,
    lvlh_rotation,
    lvlh_to_eci,
    perturbed_acceleration,
    roe_to_elements,
)
from formation_ftc.core.vector3 import norm3, sq_norm3
from formation_ftc.sim.components import Plant, Signal, TruthInputs, component, static

__all__ = ["InertialFormationPlant"]

VEC = ("spacecraft", "axis")
_SUN_X = np.array([1.0, 0.0, 0.0])


@component
class InertialFormationPlant(Plant):
    """N point-mass spacecraft and a virtual chief propagated in the Earth-centred inertial frame.

    State ``{"chief": (6,), "deputies": (N, 6)}``: ECI position [m] and velocity [m/s]. Every body
    follows eqs. (1)-(4) of :mod:`formation_ftc.core.dynamics.orbital_truth` (two-body gravity, plus J2,
    drag with a co-rotating exponential atmosphere and cannonball SRP when the static flags ``j2``,
    ``drag``, ``srp`` are on). The chief is a virtual spacecraft (no thrust) propagated with the same
    model and its own ballistic and SRP coefficients. Deputy i moves under::

        r_i'' = a_nat(r_i, v_i) + R_c(t)^T (F_i + h_i(t)) / m_i

    with the applied force F_i [N] (after the actuator's faults and saturation) and the disturbance
    expressions h_i(t) [N], both given in the **chief's LVLH axes** (x radial, y along-track, z orbit
    normal) and rotated to ECI with the chief's instantaneous LVLH rotation R_c. Assumption: each
    deputy's thrusters are held aligned with the chief's LVLH axes (for a formation of size d the chief
    and deputy LVLH frames differ by about d / |r_c| rad, 1.4e-4 rad for 1 km at 7,000 km).

    What the rest of the loop sees is the deputies' state relative to the chief in the chief's LVLH
    frame (:meth:`position`, :meth:`velocity`, (N, 3) each, as the relative-state plants), with the
    relative velocity taken in the frame rotating at omega = r_c x v_c / |r_c|^2.

    Initial condition: the chief's classical elements and per-deputy LVLH offsets, or per-deputy
    quasi-nonsingular relative orbital elements (``initial_roe``, see
    :func:`~formation_ftc.core.dynamics.orbital_truth.roe_to_elements`); mapped to ECI when the run
    starts, so campaigns may vary them. Usage integrals: the commanded delta-v
    int ||u_i|| / m_i dt [m/s] and effort int ||u_i||^2 dt [N^2 s].
    """

    mass: Any  # (N,) [kg]
    chief_elements: Any  # (6,) a [m], e [-], i, RAAN, argp, true anomaly [rad]
    initial_state_lvlh: Any  # (N, 6) LVLH offsets of the deputies [m, m/s]
    ballistic_coefficient: Any  # (N,) C_D A / m [m^2/kg]
    chief_ballistic_coefficient: Any  # () C_D A / m of the virtual chief [m^2/kg]
    srp_coefficient: Any  # (N,) C_R A / m [m^2/kg]
    chief_srp_coefficient: Any  # () [m^2/kg]
    sun_direction: Any = dataclasses.field(
        default_factory=lambda: _SUN_X.copy()
    )  # (3,) ECI direction towards the Sun [-]
    density_table: Any = dataclasses.field(
        default_factory=EXPONENTIAL_ATMOSPHERE.copy
    )  # (K, 3) [h_0 m, rho_0 kg/m^3, H m]
    mu: Any = MU_EARTH  # [m^3/s^2]
    j2_coefficient: Any = J2_EARTH  # [-]
    earth_radius: Any = R_EARTH  # [m]
    earth_rotation_rate: Any = OMEGA_EARTH  # [rad/s]
    solar_pressure: Any = SOLAR_PRESSURE  # [N/m^2]
    #: (N, 6) dimensionless relative orbital elements of the deputies (da, dl, dex, dey, dix, diy); when
    #: given they replace initial_state_lvlh as the initial condition
    initial_roe: Any = None
    #: (2,) standard deviations of a Gaussian dispersion added to initial_state_lvlh: position [m] and
    #: velocity [m/s] per axis, drawn inside the run from ``dispersion_seed`` (so a campaign varies the
    #: initial errors of every spacecraft through one number)
    initial_dispersion: Any = dataclasses.field(default_factory=lambda: np.zeros(2))
    dispersion_seed: Any = 0.0  # [-] integer-valued
    j2: bool = static(default=True)
    drag: bool = static(default=False)
    srp: bool = static(default=False)
    disturbance_force: tuple[str, str, str] = static(default=("0", "0", "0"))  # h_i(t) LVLH [N]

    @property
    def count(self) -> int:
        return int(np.shape(self.mass)[0])

    def initial_state(self):
        el = jnp.asarray(self.chief_elements)
        chief = elements_to_eci(el[0], el[1], el[2], el[3], el[4], el[5], self.mu)
        if self.initial_roe is not None:
            deputies = elements_to_eci(*roe_to_elements(tuple(el), self.initial_roe), self.mu)
            return {"chief": chief, "deputies": deputies}
        return {
            "chief": chief,
            "deputies": lvlh_to_eci(chief, self.initial_state_lvlh + self.dispersion()),
        }

    def dispersion(self):
        """(N, 6) LVLH initial-state dispersion [m, m/s]: standard normal draws from ``dispersion_seed``
        scaled by ``initial_dispersion`` (zero when both deviations are zero)."""
        key = jax.random.PRNGKey(jnp.asarray(self.dispersion_seed).astype(jnp.uint32))
        z = jax.random.normal(key, (self.count, 6), dtype=jnp.float64)
        std = jnp.asarray(self.initial_dispersion)
        return z * jnp.concatenate([jnp.full(3, std[0]), jnp.full(3, std[1])])

    def exogenous(self, t):
        return {"h": vector_expression(self.disturbance_force, "disturbance.force", t, self.count)}

    def _acceleration(self, s, ballistic, srp_coefficient):
        return perturbed_acceleration(
            s[..., :3],
            s[..., 3:],
            mu=self.mu,
            j2=self.j2_coefficient if self.j2 else None,
            r_earth=self.earth_radius,
            ballistic=ballistic if self.drag else None,
            table=self.density_table,
            omega_earth=self.earth_rotation_rate,
            srp_coefficient=srp_coefficient if self.srp else None,
            sun_direction=self.sun_direction,
            pressure=self.solar_pressure,
        )

    def derivative(self, t, x, inputs: TruthInputs):
        chief, dep = x["chief"], x["deputies"]
        a_chief = self._acceleration(
            chief, self.chief_ballistic_coefficient, self.chief_srp_coefficient
        )
        R = lvlh_rotation(chief[:3], chief[3:])  # ECI -> chief LVLH
        f_lvlh = (inputs.force + inputs.exogenous["h"]) / jnp.asarray(self.mass)[:, None]
        a_dep = (
            self._acceleration(dep, self.ballistic_coefficient, self.srp_coefficient) + f_lvlh @ R
        )  # R^T f for every row: LVLH -> ECI
        return {
            "chief": jnp.concatenate([chief[3:], a_chief]),
            "deputies": jnp.concatenate([dep[:, 3:], a_dep], axis=-1),
        }

    def relative_state(self, x):
        """(N, 6) LVLH relative state [m, m/s] of the deputies w.r.t. the chief."""
        return eci_to_lvlh(x["chief"], x["deputies"])

    def sensed_shapes(self) -> dict[str, tuple[int, ...]]:
        """The shapes of :meth:`sensed_state`'s arrays, known without computing the orbits (a build
        checks them without JAX): ``{"q": (N, 6)}``."""
        return {"q": (self.count, 6)}

    def sensed_state(self, x):
        """What sensors measure: ``{"q": (N, 6)}``, the LVLH relative state (so every relative-state sensor
        and every law built for the relative-state plants works on the inertial truth)."""
        return {"q": self.relative_state(x)}

    def position(self, x):
        return self.relative_state(x)[:, :3]

    def velocity(self, x):
        return self.relative_state(x)[:, 3:]

    def usage_names(self):
        return ("delta_v", "control_effort")

    def usage_rates(self, t, x, command):
        return {"delta_v": norm3(command) / self.mass, "control_effort": sq_norm3(command)}

    def signals(self):
        return (
            Signal("position", VEC, "m", "position relative to the truth chief", "LVLH"),
            Signal(
                "velocity",
                VEC,
                "m s-1",
                "velocity relative to the truth chief (rotating frame)",
                "LVLH",
            ),
            Signal(
                "chief_altitude", (), "m", "altitude of the truth chief above the spherical Earth"
            ),
            Signal("delta_v", ("spacecraft",), "m s-1", "commanded delta-v, integral of |f_i|/m_i"),
            Signal("control_effort", ("spacecraft",), "N2 s", "integral of |f_i|^2"),
        )

    def outputs(self, t, x, inputs):
        q = self.relative_state(x)
        return {
            "position": q[:, :3],
            "velocity": q[:, 3:],
            "chief_altitude": jnp.linalg.norm(x["chief"][:3]) - self.earth_radius,
        }
