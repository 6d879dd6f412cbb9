"""Conventional output-feedback FTC (COF2TC): the comparison baseline of Gui et al. 2022 (Figs. 7-9).

The paper compares with "the conventional output-feedback FTC approach proposed in [30]" but gives
neither the law nor its gains (E002-10). Following our choice this module implements the
passive, fixed-gain ("reliable") output feedback

    u = K e_y                        (pi == 1, no learning term v, no fault compensation)

with the same gain K as LOF2TC (K C = B^T P1, eq. (35)), and the optional variant
``fault_compensation=True``: ``u = K e_y - B^+ H F_hat`` (uses the ILO fault estimate).

Assumptions (stated because ref. [30] is not reproduced): same K, same measurement e_y = y0 - y, same
sampling (u held over the step), no adaptation and no disturbance compensation; the expected outcome is
a steady x offset of about F_x / K_11 = 0.5 / 0.0063 = 79 m after the 1500 s bias fault and a z
oscillation of about 37 m after 2000 s. Units as in
:mod:`formation_ftc.blocks.controllers.learning_output_feedback`.
"""

from __future__ import annotations

import jax

from formation_ftc.core.linear import matvec

__all__ = ["cof2tc_law"]


def cof2tc_law(e_y: jax.Array, F_hat: jax.Array, K, BpH, fault_compensation: bool) -> jax.Array:
    """``u = K e_y`` [m/s^2] (optionally ``- B^+ H F_hat``); broadcasts over leading axes."""
    u = matvec(K, e_y)
    if fault_compensation:
        u = u - matvec(BpH, F_hat)
    return u
