"""Controller ``gui2022-cof2tc``: the conventional output-feedback FTC (COF2TC), the comparison
baseline of Gui et al. 2022 (Figs. 7-9), an acceleration law on a CW nominal orbit.

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
:mod:`formation_ftc.components.controllers.gui2022_lof2tc`.

What the Gui2022 laws share (the nominal orbit, the on-board CW model, acceleration -> force, the
gains) is in :mod:`formation_ftc.components.controllers._output_feedback`. With ``fault_compensation``
the law needs the fault estimate of an estimator (the capability ``thruster-fault-estimate``).
"""

from __future__ import annotations

from typing import Any

import jax
from pydantic import Field

from formation_ftc.components._registry import BuildContext, register
from formation_ftc.components.controllers._output_feedback import (
    NominalOrbitTracking,
    OutputFeedbackSection,
    _on_plant,
    _output_feedback_fields,
)
from formation_ftc.core.linear import matvec
from formation_ftc.sim.components import Controller, FlightInputs, component, static

__all__ = ["cof2tc_law", "ConventionalOutputFeedbackController", "Cof2tcSection"]


def cof2tc_law(e_y: jax.Array, F_hat: jax.Array, K, BpH, fault_compensation: bool) -> jax.Array:
    """``u = K e_y`` [m/s^2] (optionally ``- B^+ H F_hat``); broadcasts over leading axes.

    Parameters
    ----------
    e_y : jax.Array, shape (..., p)
        Measured tracking error [m, m/s].
    F_hat : jax.Array, shape (..., m)
        Fault estimate [m/s^2].
    K : array_like, shape (m, p)
        Gain [1/s^2, 1/s].
    BpH : array_like, shape (m, m)
        B^+ H [-].
    fault_compensation : bool
        Subtract B^+ H F_hat.

    Returns
    -------
    jax.Array
        u, shape (..., m) [m/s^2].

    Examples
    --------
    >>> import numpy as np
    >>> K = np.hstack([np.eye(3), np.zeros((3, 3))])
    >>> np.asarray(cof2tc_law(np.ones(6), np.full(3, 0.5), K, np.eye(3), True)).tolist()
    [0.5, 0.5, 0.5]
    """
    u = matvec(K, e_y)
    if fault_compensation:
        u = u - matvec(BpH, F_hat)
    return u


@component
class ConventionalOutputFeedbackController(NominalOrbitTracking):
    """COF2TC baseline: u = K e_y [m/s^2], or u = K e_y - B^+H F_hat with ``fault_compensation``."""

    K: Any = 0.0
    BpH: Any = 0.0
    fault_compensation: bool = static(default=False)

    def output(self, t, state, inputs: FlightInputs):
        q0, e_y, F_hat = self.tracking(inputs)
        u = cof2tc_law(e_y, F_hat, self.K, self.BpH, self.fault_compensation)
        return u, state, {"desired_state": q0, "tracking_error": e_y}

    def needs(self) -> dict[str, str]:
        out = super().needs()
        if self.fault_compensation:
            out["thruster-fault-estimate"] = "compensate it (fault_compensation = true)"
        return out


class Cof2tcSection(OutputFeedbackSection):
    """COF2TC: u = K e_y, or u = K e_y - B^+H F_hat with ``fault_compensation``."""

    fault_compensation: bool = Field(
        False, description="Subtract the estimator's fault estimate F_hat."
    )


def _build(sec: Cof2tcSection, ctx: BuildContext) -> Controller:
    """The controller of a validated ``[controller] type = "gui2022-cof2tc"`` section."""
    law = ConventionalOutputFeedbackController(
        **_output_feedback_fields(sec, ctx), fault_compensation=sec.fault_compensation
    )
    return _on_plant(law, sec, ctx)


register(
    "controller",
    "gui2022-cof2tc",
    Cof2tcSection,
    _build,
    "Gui2022 COF2TC baseline u = K e_y (optionally - F_hat) on a CW nominal orbit",
)
