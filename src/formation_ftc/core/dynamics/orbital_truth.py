"""High-fidelity orbital truth: Earth-centred inertial (ECI) translation with J2, drag and SRP.

Every function is pure ``jax.numpy`` (float64, SI units: metres, seconds, kilograms, radians) and works
on stacked inputs (``(..., 3)`` positions and velocities) and traced parameters (Monte Carlo).

Model (per unit mass, ECI, z axis along Earth's rotation axis)::

    r'' = -mu r / |r|^3                          two-body                          (1)
        + a_J2(r)                                zonal J2 term                     (2)
        - 1/2 rho(h) B |v_rel| v_rel             drag, v_rel = v - omega_E x r     (3)
        - P_sun C_R A/m s_hat                    cannonball SRP, s_hat: to the Sun (4)
        + f / m                                  applied force f [N]

    a_J2 = -3/2 J2 mu R_E^2 / r^5 [x (1 - 5 z^2/r^2), y (1 - 5 z^2/r^2), z (3 - 5 z^2/r^2)]   (2)
    U_J2 =  1/2 J2 mu R_E^2 / r^3 (3 z^2/r^2 - 1)   (a_J2 = -grad U_J2)                      (5)

Earth constants (module constants; every function also takes them as arguments):

* ``MU_EARTH`` = 3.986004418e14 m^3/s^2 -- WGS-84 gravitational parameter (the package-wide value of
  :mod:`formation_ftc.core.orbit`);
* ``R_EARTH`` = 6378137.0 m -- WGS-84 equatorial radius (used as the J2 reference radius and for the
  altitude of the spherical-Earth atmosphere);
* ``J2_EARTH`` = 1.0826266835531513e-3 -- EGM96: J2 = -sqrt(5) C20bar with the normalised
  C20bar = -4.84165371736e-4;
* ``OMEGA_EARTH`` = 7.292115e-5 rad/s -- WGS-84 Earth rotation rate (co-rotating atmosphere);
* ``SOLAR_PRESSURE`` = 1361 / 299792458 = 4.5398e-6 N/m^2 -- total solar irradiance 1361 W/m^2 at
  1 AU (Kopp & Lean 2011) over the speed of light.

Atmosphere: the piecewise exponential model of Vallado (Fundamentals of Astrodynamics and Applications,
4th ed. 2013, Table 8-4, from CIRA-72): rho(h) = rho_0 exp(-(h - h_0) / H) with (h_0, rho_0, H) of the
band containing the altitude h = |r| - R_E (spherical Earth), see :data:`EXPONENTIAL_ATMOSPHERE`. A
single exponential is the one-row table ``[[h_0, rho_0, H]]``. Below the first base altitude the first
row is extrapolated. The atmosphere co-rotates with the Earth (omega_E about the ECI z axis).

SRP: cannonball model with a fixed Sun direction in ECI and no eclipse (the spacecraft is always lit);
the pressure is the 1 AU value (no Sun-distance variation).

Frames: the chief's LVLH frame has x radial (outward), y along-track (in the orbit plane, completing the
triad), z along the orbit normal h = r x v -- the convention of
:mod:`formation_ftc.core.dynamics.relative_lvlh`. Relative velocities are taken in the rotating frame
with the angular velocity omega = r x v / |r|^2 of the chief (exact for a Keplerian chief; under J2 or
drag the frame's small rotation about the radial axis, of order |r| a_normal / |h|, is not included).
"""

from __future__ import annotations

import jax.numpy as jnp

from formation_ftc.core.constants import EXPONENTIAL_ATMOSPHERE, MU_EARTH, R_EARTH
from formation_ftc.core.dynamics.two_body import gravity_acceleration, specific_energy
from formation_ftc.core.vector3 import matrix3

__all__ = [
    "MU_EARTH",
    "R_EARTH",
    "J2_EARTH",
    "OMEGA_EARTH",
    "SOLAR_PRESSURE",
    "EXPONENTIAL_ATMOSPHERE",
    "j2_acceleration",
    "j2_potential",
    "specific_energy_j2",
    "atmospheric_density",
    "drag_acceleration",
    "srp_acceleration",
    "perturbed_acceleration",
    "elements_to_eci",
    "eci_to_elements",
    "true_to_mean_anomaly",
    "mean_to_true_anomaly",
    "roe_to_elements",
    "elements_to_roe",
    "lvlh_rotation",
    "lvlh_angular_velocity",
    "eci_to_lvlh",
    "lvlh_to_eci",
    "j2_secular_rates",
    "drag_decay_rate_circular",
]

J2_EARTH = 1.0826266835531513e-3  # -, EGM96 (-sqrt(5) * C20bar, C20bar = -4.84165371736e-4)
OMEGA_EARTH = 7.292115e-5  # rad/s, WGS-84 rotation rate
SOLAR_PRESSURE = 1361.0 / 299792458.0  # N/m^2, TSI 1361 W/m^2 (Kopp & Lean 2011) / c


def _norm(v):
    return jnp.sqrt(jnp.sum(v * v, axis=-1, keepdims=True))


def _wrap(x):
    """``x`` wrapped to [-pi, pi) [rad]."""
    return jnp.remainder(x + jnp.pi, 2 * jnp.pi) - jnp.pi


def _rotate(R, x):
    """``R @ x`` over stacked (..., 3, 3) matrices and (..., 3) vectors."""
    return jnp.einsum("...ij,...j->...i", R, x)


# --------------------------------------------------------------------------------------- forces
def j2_acceleration(r, mu=MU_EARTH, j2=J2_EARTH, r_earth=R_EARTH):
    """Acceleration of the J2 zonal harmonic [m/s^2] (eq. (2)); ``r`` (..., 3) ECI [m]."""
    r = jnp.asarray(r)
    rn = _norm(r)
    z2 = (r[..., 2:3] / rn) ** 2
    k = -1.5 * j2 * mu * r_earth**2 / rn**5
    factors = jnp.concatenate([1.0 - 5.0 * z2, 1.0 - 5.0 * z2, 3.0 - 5.0 * z2], axis=-1)
    return k * r * factors  # eq. (2)


def j2_potential(r, mu=MU_EARTH, j2=J2_EARTH, r_earth=R_EARTH):
    """Potential energy per unit mass of the J2 term [J/kg] (eq. (5)); its negative gradient is
    :func:`j2_acceleration`. ``r`` (..., 3) ECI [m]; returns shape (...)."""
    r = jnp.asarray(r)
    rn = jnp.linalg.norm(r, axis=-1)
    return 0.5 * j2 * mu * r_earth**2 / rn**3 * (3.0 * (r[..., 2] / rn) ** 2 - 1.0)  # eq. (5)


def specific_energy_j2(state, mu=MU_EARTH, j2=J2_EARTH, r_earth=R_EARTH):
    """Total specific energy |v|^2/2 - mu/|r| + U_J2 [J/kg] of ``state`` (..., 6) [m, m/s]; conserved by
    two-body + J2 motion (the J2 field is axisymmetric about the ECI z axis, hence time-invariant)."""
    state = jnp.asarray(state)
    return specific_energy(state, mu) + j2_potential(state[..., :3], mu, j2, r_earth)


def atmospheric_density(altitude, table=EXPONENTIAL_ATMOSPHERE):
    """Piecewise exponential density rho(h) = rho_0 exp(-(h - h_0)/H) [kg/m^3] at altitude ``altitude`` [m].

    ``table`` (K, 3) rows [h_0 [m], rho_0 [kg/m^3], H [m]] sorted by h_0; the band is the last row with
    h_0 <= h (the first row below its base altitude)."""
    table, h = jnp.asarray(table), jnp.asarray(altitude)
    idx = jnp.clip(jnp.searchsorted(table[:, 0], h, side="right") - 1, 0, table.shape[0] - 1)
    row = table[idx]
    return row[..., 1] * jnp.exp(-(h - row[..., 0]) / row[..., 2])


def drag_acceleration(
    r, v, ballistic, table=EXPONENTIAL_ATMOSPHERE, omega_earth=OMEGA_EARTH, r_earth=R_EARTH
):
    """Drag -1/2 rho B |v_rel| v_rel [m/s^2] with v_rel = v - omega_E x r (eq. (3)).

    Parameters
    ----------
    r, v : (..., 3) ECI position [m] and velocity [m/s]
    ballistic : B = C_D A / m [m^2/kg], shape (...) (broadcast against the leading axes)
    table : density table of :func:`atmospheric_density`
    omega_earth : Earth rotation rate about the ECI z axis [rad/s]
    r_earth : radius of the spherical Earth for the altitude [m]
    """
    r, v = jnp.asarray(r), jnp.asarray(v)
    rho = atmospheric_density(jnp.linalg.norm(r, axis=-1) - r_earth, table)
    w = jnp.array([0.0, 0.0, 1.0]) * omega_earth
    v_rel = v - jnp.cross(jnp.broadcast_to(w, r.shape), r)
    return (-0.5 * rho * jnp.asarray(ballistic))[..., None] * _norm(v_rel) * v_rel  # eq. (3)


def srp_acceleration(srp_coefficient, sun_direction, pressure=SOLAR_PRESSURE):
    """Cannonball SRP -P C_R A/m s_hat [m/s^2] (eq. (4)), no eclipse, fixed Sun direction.

    ``srp_coefficient`` C_R A / m [m^2/kg], shape (...); ``sun_direction`` (3,) ECI vector towards the Sun
    (normalised here); ``pressure`` P [N/m^2]. Returns (..., 3)."""
    s = jnp.asarray(sun_direction)
    s = s / jnp.linalg.norm(s)
    return (-pressure * jnp.asarray(srp_coefficient))[..., None] * s  # eq. (4)


def perturbed_acceleration(
    r,
    v,
    *,
    mu=MU_EARTH,
    j2=None,
    r_earth=R_EARTH,
    ballistic=None,
    table=EXPONENTIAL_ATMOSPHERE,
    omega_earth=OMEGA_EARTH,
    srp_coefficient=None,
    sun_direction=(1.0, 0.0, 0.0),
    pressure=SOLAR_PRESSURE,
):
    """Natural acceleration (1) (:func:`~formation_ftc.core.dynamics.two_body.gravity_acceleration`)
    + optional (2)-(4) [m/s^2]; a term is off when its parameter is None
    (``j2``, ``ballistic``, ``srp_coefficient``). Shapes as in the individual terms."""
    a = gravity_acceleration(r, mu)  # eq. (1)
    if j2 is not None:
        a = a + j2_acceleration(r, mu, j2, r_earth)
    if ballistic is not None:
        a = a + drag_acceleration(r, v, ballistic, table, omega_earth, r_earth)
    if srp_coefficient is not None:
        a = a + srp_acceleration(srp_coefficient, sun_direction, pressure)
    return a


# ----------------------------------------------------------------------------------- elements
def _rot(angle, axis: int):
    """Rotation by ``angle`` [rad] about the coordinate axis ``axis`` (0: x, 2: z), (..., 3, 3)."""
    c, s = jnp.cos(angle), jnp.sin(angle)
    z, o = jnp.zeros_like(c), jnp.ones_like(c)
    rows = [[c, -s, z], [s, c, z], [z, z, o]] if axis == 2 else [[o, z, z], [z, c, -s], [z, s, c]]
    return matrix3(rows)


def elements_to_eci(a, e, i, raan, argp, nu, mu=MU_EARTH):
    """ECI state [r, v] (..., 6) [m, m/s] from classical orbital elements.

    Parameters
    ----------
    a : semi-major axis [m]; e : eccentricity [-] (0 <= e < 1); i : inclination [rad];
    raan : right ascension of the ascending node [rad]; argp : argument of perigee [rad];
    nu : true anomaly [rad]; mu : gravitational parameter [m^3/s^2]
    """
    a, e, nu = jnp.asarray(a), jnp.asarray(e), jnp.asarray(nu)
    p = a * (1.0 - e**2)
    r = p / (1.0 + e * jnp.cos(nu))
    r_pf = jnp.stack([r * jnp.cos(nu), r * jnp.sin(nu), jnp.zeros_like(r)], -1)  # perifocal frame
    k = jnp.sqrt(mu / p)
    v_pf = jnp.stack([-k * jnp.sin(nu), k * (e + jnp.cos(nu)), jnp.zeros_like(r)], -1)
    Q = _rot(raan, 2) @ _rot(i, 0) @ _rot(argp, 2)  # perifocal -> ECI
    return jnp.concatenate([_rotate(Q, r_pf), _rotate(Q, v_pf)], -1)


def eci_to_elements(state, mu=MU_EARTH):
    """Osculating classical elements ``(a, e, i, raan, argp, nu)`` [m, -, rad, rad, rad, rad] of an ECI
    state (..., 6). Angles in [0, 2 pi) (i in [0, pi]). Singular cases stay finite: for e = 0 the
    argument of perigee follows the rounding direction of the eccentricity vector (arbitrary); for
    i = 0 the node line is taken along the ECI x axis (raan = 0)."""
    state = jnp.asarray(state)
    r, v = state[..., :3], state[..., 3:]
    rn = jnp.linalg.norm(r, axis=-1)
    h = jnp.cross(r, v)
    hn = jnp.linalg.norm(h, axis=-1)
    n_vec = jnp.stack(
        [-h[..., 1], h[..., 0], jnp.zeros_like(hn)], -1
    )  # z x h: towards the ascending node
    e_vec = jnp.cross(v, h) / mu - r / rn[..., None]
    e = jnp.linalg.norm(e_vec, axis=-1)
    energy = 0.5 * jnp.sum(v * v, axis=-1) - mu / rn
    a = -mu / (2.0 * energy)
    i = jnp.arccos(jnp.clip(h[..., 2] / hn, -1.0, 1.0))
    raan = jnp.mod(jnp.arctan2(n_vec[..., 1], n_vec[..., 0]), 2 * jnp.pi)
    # angles in the orbit plane, measured from the node line with the orbit normal as the axis
    hz = h / hn[..., None]
    n_norm = jnp.linalg.norm(n_vec, axis=-1, keepdims=True)
    # equatorial orbit: no node line; measure from the ECI x axis (raan = 0)
    n_hat = jnp.where(
        n_norm > 0, n_vec / jnp.where(n_norm > 0, n_norm, 1.0), jnp.array([1.0, 0.0, 0.0])
    )
    m_hat = jnp.cross(hz, n_hat)

    def angle(u):
        return jnp.arctan2(jnp.sum(u * m_hat, -1), jnp.sum(u * n_hat, -1))

    argp = jnp.mod(angle(e_vec), 2 * jnp.pi)
    nu = jnp.mod(angle(r) - angle(e_vec), 2 * jnp.pi)
    return a, e, i, raan, argp, nu


def true_to_mean_anomaly(nu, e):
    """Mean anomaly M [rad] from the true anomaly ``nu`` [rad] (eccentric anomaly, Kepler's equation);
    whole revolutions of ``nu`` are kept."""
    nu = jnp.asarray(nu)
    nu_w = _wrap(nu)
    E = 2.0 * jnp.arctan2(
        jnp.sqrt(1.0 - e) * jnp.sin(nu_w / 2), jnp.sqrt(1.0 + e) * jnp.cos(nu_w / 2)
    )
    return E - e * jnp.sin(E) + (nu - nu_w)


def mean_to_true_anomaly(M, e, iterations: int = 40):
    """True anomaly [rad] from the mean anomaly ``M`` [rad]: Newton on Kepler's equation M = E - e sin E
    (a fixed number of iterations, traceable; quadratic convergence for 0 <= e < 0.9 from the start
    E = M + e sin M, or pi for e > 0.8)."""
    M = jnp.asarray(M)
    Mr = _wrap(M)
    E = jnp.where(e < 0.8, Mr + e * jnp.sin(Mr), jnp.pi * jnp.sign(Mr))
    for _ in range(iterations):
        E = E - (E - e * jnp.sin(E) - Mr) / (1.0 - e * jnp.cos(E))
    nu = 2.0 * jnp.arctan2(jnp.sqrt(1.0 + e) * jnp.sin(E / 2), jnp.sqrt(1.0 - e) * jnp.cos(E / 2))
    return nu + (M - Mr)


def roe_to_elements(chief, roe, mu=MU_EARTH):
    """Deputy classical elements from the chief's and quasi-nonsingular relative orbital elements.

    ``chief`` = (a, e, i, RAAN, argp, nu) [m, -, rad, rad, rad, rad]; ``roe`` (..., 6) dimensionless
    (divide metres by a)::

        da  = (a_d - a_c) / a_c
        dl  = (u_d - u_c) + (RAAN_d - RAAN_c) cos i_c            (u = argp + M, mean argument of latitude)
        dex = e_d cos argp_d - e_c cos argp_c,   dey = e_d sin argp_d - e_c sin argp_c
        dix = i_d - i_c,                         diy = (RAAN_d - RAAN_c) sin i_c

    (D'Amico's definition.) Singular for sin i_c = 0 with diy != 0. Returns a tuple of six (...) arrays.
    """
    del mu
    a, e, i, raan, argp, nu = (jnp.asarray(c) for c in chief)
    roe = jnp.asarray(roe)
    da, dl, dex, dey, dix, diy = (roe[..., k] for k in range(6))
    u_c = argp + true_to_mean_anomaly(nu, e)
    ex, ey = e * jnp.cos(argp) + dex, e * jnp.sin(argp) + dey
    e_d = jnp.sqrt(ex**2 + ey**2)
    argp_d = jnp.arctan2(ey, ex)
    d_raan = diy / jnp.sin(i)
    u_d = u_c + dl - d_raan * jnp.cos(i)
    nu_d = mean_to_true_anomaly(u_d - argp_d, e_d)
    return a * (1.0 + da), e_d, i + dix, raan + d_raan, argp_d, nu_d


def elements_to_roe(chief, deputy):
    """Inverse of :func:`roe_to_elements`: (..., 6) dimensionless ROE of ``deputy`` elements w.r.t.
    ``chief`` (both (a, e, i, RAAN, argp, nu)); angle differences wrapped to (-pi, pi]."""
    a, e, i, raan, argp, nu = (jnp.asarray(c) for c in chief)
    ad, ed, id_, raand, argpd, nud = (jnp.asarray(c) for c in deputy)
    d_raan = _wrap(raand - raan)
    du = _wrap(argpd + true_to_mean_anomaly(nud, ed) - argp - true_to_mean_anomaly(nu, e))
    return jnp.stack(
        [
            ad / a - 1.0,
            du + d_raan * jnp.cos(i),
            ed * jnp.cos(argpd) - e * jnp.cos(argp),
            ed * jnp.sin(argpd) - e * jnp.sin(argp),
            id_ - i,
            d_raan * jnp.sin(i),
        ],
        axis=-1,
    )


# --------------------------------------------------------------------------------------- LVLH
def lvlh_rotation(r_chief, v_chief):
    """Rotation ECI -> chief LVLH (..., 3, 3): rows are the LVLH unit vectors (x radial, y along-track,
    z orbit normal) in ECI coordinates, so ``rho = R @ dr`` and ``dr = R.T @ rho``."""
    r_chief, v_chief = jnp.asarray(r_chief), jnp.asarray(v_chief)
    h = jnp.cross(r_chief, v_chief)
    ex = r_chief / _norm(r_chief)
    ez = h / _norm(h)
    ey = jnp.cross(ez, ex)
    return jnp.stack([ex, ey, ez], axis=-2)


def lvlh_angular_velocity(r_chief, v_chief):
    """Angular velocity of the chief LVLH frame, omega = r x v / |r|^2 [rad/s], in ECI (..., 3)."""
    r_chief, v_chief = jnp.asarray(r_chief), jnp.asarray(v_chief)
    return jnp.cross(r_chief, v_chief) / jnp.sum(r_chief**2, axis=-1, keepdims=True)


def _chief_frame(chief):
    """The chief's position, velocity, rotation ECI -> LVLH and LVLH angular velocity."""
    chief = jnp.asarray(chief)
    rc, vc = chief[..., :3], chief[..., 3:]
    return rc, vc, lvlh_rotation(rc, vc), lvlh_angular_velocity(rc, vc)


def eci_to_lvlh(chief, deputy):
    """Relative state of ``deputy`` (..., 6) in the LVLH frame of ``chief`` (6,) or (..., 6) [m, m/s]::

        rho = R (r_d - r_c),   rho_dot = R (v_d - v_c - omega x (r_d - r_c))     (rotating frame)

    Returns (..., 6) ``[rho, rho_dot]``."""
    deputy = jnp.asarray(deputy)
    rc, vc, R, w = _chief_frame(chief)
    dr = deputy[..., :3] - rc
    dv = deputy[..., 3:] - vc - jnp.cross(jnp.broadcast_to(w, dr.shape), dr)
    return jnp.concatenate([_rotate(R, dr), _rotate(R, dv)], -1)


def lvlh_to_eci(chief, relative):
    """Inverse of :func:`eci_to_lvlh`: deputy ECI state (..., 6) from the chief (6,) and LVLH offsets
    ``relative`` (..., 6) [m, m/s]: r_d = r_c + R^T rho, v_d = v_c + R^T rho_dot + omega x (R^T rho)."""
    relative = jnp.asarray(relative)
    rc, vc, R, w = _chief_frame(chief)
    dr = jnp.einsum("...ji,...j->...i", R, relative[..., :3])
    dv = jnp.einsum("...ji,...j->...i", R, relative[..., 3:]) + jnp.cross(
        jnp.broadcast_to(w, dr.shape), dr
    )
    return jnp.concatenate([rc + dr, vc + dv], -1)


# ------------------------------------------------------------------------------ analytic rates
def j2_secular_rates(a, e, i, mu=MU_EARTH, j2=J2_EARTH, r_earth=R_EARTH):
    """First-order mean secular rates (d RAAN/dt, d argp/dt) [rad/s] of the J2 term::

        dRAAN/dt = -3/2 n J2 (R_E/p)^2 cos i                 (6)
        dargp/dt =  3/4 n J2 (R_E/p)^2 (5 cos^2 i - 1)        (7)

    with n = sqrt(mu/a^3) and p = a (1 - e^2) (mean elements: a [m], e [-], i [rad])."""
    n = jnp.sqrt(mu / jnp.asarray(a) ** 3)
    k = n * j2 * (r_earth / (a * (1.0 - e**2))) ** 2
    return -1.5 * k * jnp.cos(i), 0.75 * k * (5.0 * jnp.cos(i) ** 2 - 1.0)  # eqs. (6), (7)


def drag_decay_rate_circular(a, ballistic, density, mu=MU_EARTH):
    """da/dt = -rho B sqrt(mu a) [m/s] of a circular orbit (non-rotating atmosphere; the co-rotation
    changes |v_rel| by the factor ~ 1 - omega_E r cos i / v, hence the rate by about its square): a [m],
    B = C_D A/m [m^2/kg], rho [kg/m^3]."""
    return -density * ballistic * jnp.sqrt(mu * a)
