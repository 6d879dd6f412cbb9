"""Values printed in Gui et al. 2022 (Appl. Sci. 12, 2022), section 5, and our documented choices for the
data the paper does not give (E002-10), as the checks, the report and the tests read them (the scenario
files ``gui2022-*.toml`` state the same numbers as data)."""

from __future__ import annotations

import numpy as np

__all__ = [
    "N_MEAN_MOTION",
    "A0",
    "L1_PRINTED",
    "L2_PRINTED",
    "P1_PRINTED",
    "K_PRINTED",
    "Q1_PRINTED",
    "Q2_PRINTED",
    "GAMMA_PRINTED",
    "Q0_INITIAL",
    "CARE_Q_SCALE",
    "ESTIMATE_OFFSET",
]

N_MEAN_MOTION = 0.0015  # [rad/s], section 5
A0 = 1.2e-3  # perturbation amplitude [m/s^2] (printed "N", per unit mass: E002-03)

# Section 5.1 (observer) -- printed to 4 decimals
L1_PRINTED = np.array(
    [
        [4.5471, 0, 0, 1.0, 0, 0],
        [0, 4.5471, 0, 0, 1.0, 0],
        [0, 0, 4.5471, 0, 0, 1.0],
        [0, 0, 0, 4.5470, 0.0030, 0],
        [0, 0, 0, -0.0030, 4.5471, 0],
        [0, 0, 0, 0, 0, 4.5471],
    ]
)
L2_PRINTED = np.array(
    [
        [0, 0, 0, 456.2710, 0, 0],
        [0, 0, 0, 0, 456.2530, 0],
        [0, 0, 0, 0, 0, 456.2642],
    ]
)
Q1_PRINTED = np.array([0.99, 0.99, 0.99])
Q2_PRINTED = 0.999
GAMMA_PRINTED = 3.231e-3

# Section 5.2 (controller)
P1_PRINTED = np.array(
    [
        [0.0007, 0, 0, 0.0063, 0.0002, 0],
        [0, 0.0007, 0, -0.0002, 0.0063, 0],
        [0, 0, 0.0007, 0, 0, 0.0063],
        [0.0063, -0.0002, 0, 0.1127, 0, 0],
        [0.0002, 0.0063, 0, 0, 0.1126, 0],
        [0, 0, 0.0063, 0, 0, 0.1126],
    ]
)
K_PRINTED = np.array(
    [
        [0.0063, -0.0002, 0, 0.1127, 0, 0],
        [0.0002, 0.0063, 0, 0, 0.1126, 0],
        [0, 0, 0.0063, 0, 0, 0.1126],
    ]
)
Q0_INITIAL = np.array([-15.0, -505.0, 20.0, -0.37875, 0.045, 0.0])
CARE_Q_SCALE = 4e-5  # Q = 4e-5 I6 reproduces the printed P1 (E002-05) [DERIVED]
ESTIMATE_OFFSET = np.array(
    [10.0, -10.0, 5.0, 0.1, -0.1, 0.05]
)  # q_hat(0) - q(0) for Figs. 4-5 [CHOICE]
