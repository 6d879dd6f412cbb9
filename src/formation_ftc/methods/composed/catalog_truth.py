"""Catalog: the high-fidelity orbital truth plant (ECI, J2, drag, SRP) and its LVLH relative-state sensors."""

from __future__ import annotations

import math

import numpy as np
from pydantic import Field, model_validator

from formation_ftc.components._sections import Vec3, Vec3Expr
from formation_ftc.components._sections import per_axis as _per_axis
from formation_ftc.config.base import StrictModel
from formation_ftc.core.constants import EXPONENTIAL_ATMOSPHERE, MU_EARTH, R_EARTH
from formation_ftc.methods.composed import BuildContext, per_spacecraft, register_component_type
from formation_ftc.sim.contract import as_float

__all__ = ["OrbitalTruthSection", "LvlhRelativeStateSection"]


class OrbitalTruthSection(StrictModel):
    """Chief classical elements + per-deputy LVLH offsets (``initial_position``, ``initial_velocity``) or
    relative orbital elements (``initial_roe``); forces (applied and ``disturbance_force``) are in the
    chief's LVLH axes."""

    mass: list[float] = Field(description="True mass of each spacecraft [kg], > 0.")
    initial_position: list[Vec3] | None = Field(
        None,
        description="Initial LVLH offset of each spacecraft from the chief [m] (or give initial_roe).",
    )
    initial_velocity: list[Vec3] | None = Field(
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

    semi_major_axis: float = Field(
        gt=R_EARTH, description=f"Chief semi-major axis [m], > R_E = {R_EARTH} m."
    )
    eccentricity: float = Field(
        0.0, ge=0, lt=0.9, description="Chief eccentricity [-], in [0, 0.9)."
    )
    inclination: float = Field(
        0.0, ge=0, le=math.pi, description="Chief inclination [rad], in [0, pi]."
    )
    raan: float = Field(0.0, description="Chief right ascension of the ascending node [rad].")
    arg_perigee: float = Field(0.0, description="Chief argument of perigee [rad].")
    true_anomaly: float = Field(0.0, description="Chief true anomaly at t = 0 [rad].")
    j2: bool = Field(True, description="Include the J2 zonal harmonic.")
    drag: bool = Field(
        False, description="Include drag (exponential atmosphere co-rotating with the Earth)."
    )
    srp: bool = Field(
        False, description="Include cannonball solar radiation pressure (fixed Sun, no eclipse)."
    )
    ballistic_coefficient: float | list[float] = Field(
        0.02,
        description="B = C_D A / m of each spacecraft [m^2/kg], > 0 (one number or one per spacecraft).",
    )
    chief_ballistic_coefficient: float | None = Field(
        None,
        gt=0,
        description="B of the virtual chief [m^2/kg] (default: mean of the spacecraft's).",
    )
    srp_coefficient: float | list[float] = Field(
        0.015,
        description="C_R A / m of each spacecraft [m^2/kg], >= 0 (one number or one per spacecraft).",
    )
    chief_srp_coefficient: float | None = Field(
        None,
        ge=0,
        description="C_R A / m of the virtual chief [m^2/kg] (default: mean of the spacecraft's).",
    )
    sun_direction: tuple[float, float, float] = Field(
        (1.0, 0.0, 0.0), description="Direction towards the Sun in ECI [-] (normalised; fixed)."
    )
    density_base: float | None = Field(
        None,
        gt=0,
        description="Single-exponential atmosphere: density at density_base_altitude [kg/m^3] "
        "(default: Vallado's piecewise exponential table).",
    )
    density_base_altitude: float = Field(
        0.0, ge=0, description="Base altitude of the single exponential [m]."
    )
    density_scale_height: float = Field(
        60e3, gt=0, description="Scale height of the single exponential [m]."
    )
    mu: float = Field(MU_EARTH, gt=0, description="Gravitational parameter [m^3/s^2].")
    initial_position_std: float = Field(
        0.0,
        ge=0,
        description=(
            "Std of a Gaussian dispersion of every deputy's initial LVLH position, per axis [m] (drawn in the run "
            "from dispersion_seed; LVLH initial conditions only)."
        ),
    )
    initial_velocity_std: float = Field(
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
        if (self.initial_position is None) == (self.initial_roe is None):
            raise ValueError(
                "initial_position: give either initial_position (LVLH offsets) or initial_roe"
            )
        if self.initial_roe is not None and (
            self.initial_position_std > 0 or self.initial_velocity_std > 0
        ):
            raise ValueError(
                "initial_position_std / initial_velocity_std: a dispersion applies to LVLH initial "
                "conditions (initial_position), not to initial_roe"
            )
        if self.initial_roe is not None and self.initial_velocity is not None:
            raise ValueError(
                "initial_velocity: not used with initial_roe (the elements fix the velocity)"
            )
        for name in ("initial_position", "initial_velocity", "initial_roe"):
            rows = getattr(self, name)
            if rows is not None and len(rows) != n:
                raise ValueError(f"{name}: {len(rows)} rows for {n} spacecraft")
        if (
            self.initial_roe is not None
            and any(r[5] != 0 for r in self.initial_roe)
            and abs(math.sin(self.inclination)) < 1e-6
        ):
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
        for name, lower_ok in (
            ("ballistic_coefficient", lambda b: b > 0),
            ("srp_coefficient", lambda b: b >= 0),
        ):
            vals = np.atleast_1d(np.asarray(getattr(self, name), float))
            if not all(lower_ok(b) and math.isfinite(b) for b in vals):
                raise ValueError(
                    f"{name}: every value must be finite and {'> 0' if name[0] == 'b' else '>= 0'} m^2/kg"
                )
        return self

    @property
    def count(self) -> int:
        return len(self.mass)

    def q0(self) -> np.ndarray:
        if self.initial_position is None:
            return np.zeros((self.count, 6))
        v0 = (
            np.zeros((self.count, 3))
            if self.initial_velocity is None
            else np.asarray(self.initial_velocity)
        )
        return np.hstack([np.asarray(self.initial_position, float), v0])

    def density_table(self) -> np.ndarray:
        if self.density_base is None:
            return EXPONENTIAL_ATMOSPHERE.copy()
        return np.array(
            [[self.density_base_altitude, self.density_base, self.density_scale_height]]
        )


def _orbital_truth(sec: OrbitalTruthSection, ctx: BuildContext):
    from formation_ftc.components.plants.orbital_truth import InertialFormationPlant

    n = sec.count
    b = per_spacecraft(sec.ballistic_coefficient, n, "plant.ballistic_coefficient")
    c = per_spacecraft(sec.srp_coefficient, n, "plant.srp_coefficient")
    b_c = (
        float(np.mean(b))
        if sec.chief_ballistic_coefficient is None
        else sec.chief_ballistic_coefficient
    )
    c_c = float(np.mean(c)) if sec.chief_srp_coefficient is None else sec.chief_srp_coefficient
    elements = [
        sec.semi_major_axis,
        sec.eccentricity,
        sec.inclination,
        sec.raan,
        sec.arg_perigee,
        sec.true_anomaly,
    ]
    return InertialFormationPlant(
        mass=as_float(sec.mass),
        chief_elements=as_float(elements),
        initial_state_lvlh=as_float(sec.q0()),
        ballistic_coefficient=as_float(b),
        chief_ballistic_coefficient=as_float(b_c),
        srp_coefficient=as_float(c),
        chief_srp_coefficient=as_float(c_c),
        sun_direction=as_float(sec.sun_direction),
        density_table=as_float(sec.density_table()),
        mu=as_float(sec.mu),
        initial_roe=None
        if sec.initial_roe is None
        else as_float(np.asarray(sec.initial_roe) / sec.semi_major_axis),
        initial_dispersion=as_float([sec.initial_position_std, sec.initial_velocity_std]),
        dispersion_seed=as_float(sec.dispersion_seed),
        j2=sec.j2,
        drag=sec.drag,
        srp=sec.srp,
        disturbance_force=sec.disturbance_force,
    )


class LvlhRelativeStateSection(StrictModel):
    position_noise_std: float = Field(0.0, ge=0, description="Std of the position noise [m].")
    velocity_noise_std: float = Field(0.0, ge=0, description="Std of the velocity noise [m/s].")
    position_bias: float | list = Field(
        0.0, description="Constant position bias: a number, 3 values (per axis) or N x 3 [m]."
    )
    velocity_bias: float | list = Field(
        0.0, description="Constant velocity bias: a number, 3 values or N x 3 [m/s]."
    )


def _lvlh_relative_state(sec: LvlhRelativeStateSection, ctx: BuildContext):
    from formation_ftc.components.sensors.lvlh_relative_state import LvlhRelativeStateSensors

    shapes = ctx.sensed_shapes()
    if shapes is not None and shapes.get("q", ())[-1:] != (6,):
        raise ValueError(
            f"sensors lvlh-relative-state measure a relative position and velocity; plant "
            f"{type(ctx.plant).__name__} has no (N, 6) relative state"
        )
    n = ctx.count
    bias = np.hstack(
        [
            _per_axis(sec.position_bias, n, "sensors.position_bias"),
            _per_axis(sec.velocity_bias, n, "sensors.velocity_bias"),
        ]
    )
    if not np.all(np.isfinite(bias)):
        raise ValueError("sensors.position_bias / velocity_bias: values must be finite")
    return LvlhRelativeStateSensors(
        count=n,
        position_noise_std=as_float(sec.position_noise_std),
        velocity_noise_std=as_float(sec.velocity_noise_std),
        bias=as_float(bias),
    )


register_component_type(
    "plant",
    "orbital-truth",
    OrbitalTruthSection,
    _orbital_truth,
    "every spacecraft and a virtual chief in ECI with J2, drag and SRP; forces in the "
    "chief's LVLH axes; sensors see the LVLH relative state",
)
register_component_type(
    "sensors",
    "lvlh-relative-state",
    LvlhRelativeStateSection,
    _lvlh_relative_state,
    "relative state in the truth chief's LVLH frame with held Gaussian noise and a "
    "constant per-axis bias",
)
