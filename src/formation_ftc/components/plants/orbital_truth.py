"""Plant ``orbital-truth``: every spacecraft and a virtual chief in ECI with J2, drag and SRP; forces in
the chief's LVLH axes; sensors see the LVLH relative state.

Provides the capabilities ``translational-state`` and ``lvlh-relative-state`` (what sensors see is the
(N, 6) LVLH relative state), ``stage-evaluation`` (RK4) and ``spacecraft-pairs`` (two or more
spacecraft). The section's chief elements, LVLH initial offsets, atmosphere and dispersion fields are
builder inputs: they are combined into the component's ``chief_elements``, ``initial_state_lvlh``,
``density_table`` and ``initial_dispersion``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Annotated, Any

import jax
import jax.numpy as jnp
import numpy as np
from pydantic import Field, model_validator

from formation_ftc.components._registry import BuildContext, builder_input, per_spacecraft, register
from formation_ftc.components._sections import (
    Vec3,
    Vec3Expr,
    check_rows,
    initial_states,
    positive_values,
    section_floats,
)
from formation_ftc.components.expressions import vector_expression
from formation_ftc.components.plants._relative_state import PointMassUsage, RelativeStatePlant
from formation_ftc.config.base import StrictModel
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
from formation_ftc.sim.components import Signal, TruthInputs, component, static
from formation_ftc.sim.contract import VEC, as_float

__all__ = ["InertialFormationPlant", "OrbitalTruthSection"]

_SUN_X = np.array([1.0, 0.0, 0.0])
#: the section's fields of the chief's classical elements, in the order of ``chief_elements``
CHIEF_ELEMENTS = "semi_major_axis eccentricity inclination raan arg_perigee true_anomaly".split()


@component
class InertialFormationPlant(PointMassUsage, RelativeStatePlant):
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
    #: (3,) ECI direction towards the Sun [-]
    sun_direction: Any = dataclasses.field(default_factory=lambda: _SUN_X.copy())
    #: (K, 3) [h_0 m, rho_0 kg/m^3, H m]
    density_table: Any = dataclasses.field(default_factory=EXPONENTIAL_ATMOSPHERE.copy)
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

    def initial_state(self):
        el = jnp.asarray(self.chief_elements)
        chief = elements_to_eci(el[0], el[1], el[2], el[3], el[4], el[5], self.mu)
        if self.initial_roe is not None:
            deputies = elements_to_eci(*roe_to_elements(tuple(el), self.initial_roe), self.mu)
        else:
            deputies = lvlh_to_eci(chief, self.initial_state_lvlh + self.dispersion())
        return {"chief": chief, "deputies": deputies}

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


class OrbitalTruthSection(StrictModel):
    """Chief classical elements + per-deputy LVLH offsets (``initial_position``, ``initial_velocity``) or
    relative orbital elements (``initial_roe``); forces (applied and ``disturbance_force``) are in the
    chief's LVLH axes."""

    mass: list[float] = Field(description="True mass of each spacecraft [kg], > 0.")
    initial_position: list[Vec3] | None = builder_input(
        None,
        description="Initial LVLH offset of each spacecraft from the chief [m] (or give initial_roe).",
    )
    initial_velocity: list[Vec3] | None = builder_input(
        None,
        description="Initial LVLH velocity (rotating frame) of each spacecraft [m/s] (default 0).",
    )
    initial_roe: list[tuple[float, float, float, float, float, float]] | None = Field(
        None,
        description="Instead of initial_position/initial_velocity: quasi-nonsingular relative orbital "
        "elements a_c (da, dlambda, dex, dey, dix, diy) of each spacecraft [m].",
    )
    disturbance_force: Vec3Expr = Field(
        ("0", "0", "0"),
        description="External force per axis in the chief's "
        "LVLH axes, expressions in t [s], i [N].",
    )

    semi_major_axis: float = builder_input(
        gt=R_EARTH, description=f"Chief semi-major axis [m], > R_E = {R_EARTH} m."
    )
    eccentricity: float = builder_input(
        0.0, ge=0, lt=0.9, description="Chief eccentricity [-], in [0, 0.9)."
    )
    inclination: float = builder_input(
        0.0, ge=0, le=math.pi, description="Chief inclination [rad], in [0, pi]."
    )
    raan: float = builder_input(
        0.0, description="Chief right ascension of the ascending node [rad]."
    )
    arg_perigee: float = builder_input(0.0, description="Chief argument of perigee [rad].")
    true_anomaly: float = builder_input(0.0, description="Chief true anomaly at t = 0 [rad].")
    j2: bool = Field(True, description="Include the J2 zonal harmonic.")
    drag: bool = Field(
        False, description="Include drag (exponential atmosphere co-rotating with the Earth)."
    )
    srp: bool = Field(
        False, description="Include cannonball solar radiation pressure (fixed Sun, no eclipse)."
    )
    ballistic_coefficient: Annotated[float | list[float], positive_values(unit=" m^2/kg")] = Field(
        0.02,
        description="B = C_D A / m of each spacecraft [m^2/kg], > 0 (one number or one per spacecraft).",
    )
    chief_ballistic_coefficient: float | None = Field(
        None,
        gt=0,
        description="B of the virtual chief [m^2/kg] (default: mean of the spacecraft's).",
    )
    srp_coefficient: Annotated[float | list[float], positive_values(unit=" m^2/kg", zero=True)] = (
        Field(
            0.015,
            description="C_R A / m of each spacecraft [m^2/kg], >= 0 (one number or one per spacecraft).",
        )
    )
    chief_srp_coefficient: float | None = Field(
        None,
        ge=0,
        description="C_R A / m of the virtual chief [m^2/kg] (default: mean of the spacecraft's).",
    )
    sun_direction: tuple[float, float, float] = Field(
        (1.0, 0.0, 0.0), description="Direction towards the Sun in ECI [-] (normalised; fixed)."
    )
    density_base: float | None = builder_input(
        None,
        gt=0,
        description="Single-exponential atmosphere: density at density_base_altitude [kg/m^3] "
        "(default: Vallado's piecewise exponential table).",
    )
    density_base_altitude: float = builder_input(
        0.0, ge=0, description="Base altitude of the single exponential [m]."
    )
    density_scale_height: float = builder_input(
        60e3, gt=0, description="Scale height of the single exponential [m]."
    )
    mu: float = Field(MU_EARTH, gt=0, description="Gravitational parameter [m^3/s^2].")
    initial_position_std: float = builder_input(
        0.0,
        ge=0,
        description=(
            "Std of a Gaussian dispersion of every deputy's initial LVLH position, per axis [m] (drawn in the run "
            "from dispersion_seed; LVLH initial conditions only)."
        ),
    )
    initial_velocity_std: float = builder_input(
        0.0,
        ge=0,
        description=(
            "Std of the dispersion of every deputy's initial LVLH velocity, per axis [m/s]."
        ),
    )
    dispersion_seed: int = Field(
        0, ge=0, le=2**31 - 1, description="Seed of the initial dispersion [-]."
    )

    @model_validator(mode="after")
    def _orbit(self):
        n = len(self.mass)
        if n < 1 or any(not (m > 0 and math.isfinite(m)) for m in self.mass):
            raise ValueError("mass: at least one spacecraft, every mass finite and > 0 kg")
        roe = self.initial_roe
        if (self.initial_position is None) == (roe is None):
            raise ValueError(
                "initial_position: give either initial_position (LVLH offsets) or initial_roe"
            )
        if roe is not None and (self.initial_position_std > 0 or self.initial_velocity_std > 0):
            raise ValueError(
                "initial_position_std / initial_velocity_std: a dispersion applies to LVLH initial "
                "conditions (initial_position), not to initial_roe"
            )
        if roe is not None and self.initial_velocity is not None:
            raise ValueError(
                "initial_velocity: not used with initial_roe (the elements fix the velocity)"
            )
        check_rows(self, ["initial_position", "initial_velocity", "initial_roe"], n)
        equatorial = abs(math.sin(self.inclination)) < 1e-6
        if roe is not None and any(r[5] != 0 for r in roe) and equatorial:
            raise ValueError(
                "initial_roe: diy != 0 needs an inclined chief (sin(inclination) = 0 here)"
            )
        rp = self.semi_major_axis * (1.0 - self.eccentricity)
        if not rp > R_EARTH:
            raise ValueError(
                f"eccentricity: perigee radius a (1 - e) = {rp:.1f} m is inside the Earth "
                f"(R_E = {R_EARTH} m); lower eccentricity or raise semi_major_axis"
            )
        if not np.linalg.norm(self.sun_direction) > 0:
            raise ValueError("sun_direction: must be a non-zero vector")
        return self

    @property
    def count(self) -> int:
        return len(self.mass)

    def q0(self) -> np.ndarray:
        if self.initial_position is None:
            return np.zeros((self.count, 6))
        return initial_states(self.initial_position, self.initial_velocity)

    def density_table(self) -> np.ndarray:
        if self.density_base is None:
            return EXPONENTIAL_ATMOSPHERE.copy()
        return np.array(
            [[self.density_base_altitude, self.density_base, self.density_scale_height]]
        )


def _build(sec: OrbitalTruthSection, ctx: BuildContext) -> InertialFormationPlant:
    """The plant of a validated ``[plant] type = "orbital-truth"`` section."""
    n = sec.count
    b = per_spacecraft(sec.ballistic_coefficient, n, "plant.ballistic_coefficient")
    c = per_spacecraft(sec.srp_coefficient, n, "plant.srp_coefficient")
    b_c, c_c = sec.chief_ballistic_coefficient, sec.chief_srp_coefficient  # default: the means
    return InertialFormationPlant(
        **section_floats(sec, "mass", "sun_direction", "mu", "dispersion_seed"),
        chief_elements=as_float([getattr(sec, name) for name in CHIEF_ELEMENTS]),
        initial_state_lvlh=as_float(sec.q0()),
        ballistic_coefficient=as_float(b),
        chief_ballistic_coefficient=as_float(np.mean(b) if b_c is None else b_c),
        srp_coefficient=as_float(c),
        chief_srp_coefficient=as_float(np.mean(c) if c_c is None else c_c),
        density_table=as_float(sec.density_table()),
        initial_roe=None
        if sec.initial_roe is None
        else as_float(np.asarray(sec.initial_roe) / sec.semi_major_axis),
        initial_dispersion=as_float([sec.initial_position_std, sec.initial_velocity_std]),
        **sec.model_dump(include={"j2", "drag", "srp", "disturbance_force"}),
    )


register(
    "plant",
    "orbital-truth",
    OrbitalTruthSection,
    _build,
    "every spacecraft and a virtual chief in ECI with J2, drag and SRP; forces in the "
    "chief's LVLH axes; sensors see the LVLH relative state",
)
