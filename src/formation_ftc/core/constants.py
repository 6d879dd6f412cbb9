"""Physical constants and the numbers that scenario sections validate against, in pure Python/NumPy
(no JAX): sections import them while ``show`` validates a scenario without building it (issue 37).
The modules that use them (:mod:`formation_ftc.core.orbit`, :mod:`formation_ftc.core.dynamics.orbital_truth`,
:mod:`formation_ftc.core.dynamics.euler_lagrange`) re-export them under their old names."""

from __future__ import annotations

import numpy as np

__all__ = [
    "EXPONENTIAL_ATMOSPHERE",
    "MU_EARTH",
    "R_EARTH",
    "SINGULAR_PITCH_LIMIT_RAD",
    "check_away_from_singularity",
]

MU_EARTH = 3.986004418e14  # m^3/s^2, standard value (our choice)
R_EARTH = 6378137.0  # m, WGS-84 equatorial radius

#: Vallado (2013) Table 8-4: rows [base altitude h_0 [m], nominal density rho_0 [kg/m^3], scale height H [m]]
EXPONENTIAL_ATMOSPHERE = np.array(
    [
        [0.0, 1.225, 7.249],
        [25.0, 3.899e-2, 6.349],
        [30.0, 1.774e-2, 6.682],
        [40.0, 3.972e-3, 7.554],
        [50.0, 1.057e-3, 8.382],
        [60.0, 3.206e-4, 7.714],
        [70.0, 8.770e-5, 6.549],
        [80.0, 1.905e-5, 5.799],
        [90.0, 3.396e-6, 5.382],
        [100.0, 5.297e-7, 5.877],
        [110.0, 9.661e-8, 7.263],
        [120.0, 2.438e-8, 9.473],
        [130.0, 8.484e-9, 12.636],
        [140.0, 3.845e-9, 16.149],
        [150.0, 2.070e-9, 22.523],
        [180.0, 5.464e-10, 29.740],
        [200.0, 2.789e-10, 37.105],
        [250.0, 7.248e-11, 45.546],
        [300.0, 2.418e-11, 53.628],
        [350.0, 9.518e-12, 53.298],
        [400.0, 3.725e-12, 58.515],
        [450.0, 1.585e-12, 60.828],
        [500.0, 6.967e-13, 63.822],
        [600.0, 1.454e-13, 71.835],
        [700.0, 3.614e-14, 88.667],
        [800.0, 1.170e-14, 124.64],
        [900.0, 5.245e-15, 181.05],
        [1000.0, 3.019e-15, 268.00],
    ]
) * np.array([1e3, 1.0, 1e3])  # km -> m for the altitudes and scale heights


SINGULAR_PITCH_LIMIT_RAD = float(np.deg2rad(85.0))


def check_away_from_singularity(
    q, field: str = "attitude", limit_rad: float = SINGULAR_PITCH_LIMIT_RAD
) -> None:
    """Raise ValueError if any pitch |theta| >= limit (default 85 deg): Euler-angle singularity.

    ``q`` is array-like (..., 3) [rad]; the message names ``field`` and the offending entry.
    """
    arr = np.asarray(q, dtype=float).reshape(-1, 3)
    bad = np.flatnonzero(np.abs(arr[:, 0]) >= limit_rad)
    if bad.size:
        i = int(bad[0])
        raise ValueError(
            f"{field}: pitch theta = {np.rad2deg(arr[i, 0]):.3f} deg (row {i}) is at or beyond "
            f"+-{np.rad2deg(limit_rad):.1f} deg. The Euler-angle EL model is singular at theta = +-90 deg "
            "(R_bar contains 1/cos(theta) and D = R_bar^-T J R_bar^-1 loses rank, Mehrabian (27), "
            "E003-08); choose |theta| < "
            f"{np.rad2deg(limit_rad):.0f} deg."
        )
