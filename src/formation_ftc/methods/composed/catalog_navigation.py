"""Catalog: relative navigation and fault detection from its residuals.

* ``[estimator] type = "relative-navigation-filter"``: the law flies on a Kalman filter's estimate;
* ``[estimator] type = "residual-fdi"``: detection and isolation of a thruster fault from the Kalman
  innovation or the parity residual, with a CUSUM or fixed-threshold test
  (:class:`~formation_ftc.components.estimators.residual_fdi.ResidualFdi`);
* ``[[evaluations]] type = "fdi-scores"``: detection delay, missed detection, false alarm and correct
  isolation against the fault-battery actuator's true fault.

The navigation filter:
A linear Kalman filter on the measured LVLH relative states with the on-board Clohessy-Wiltshire model
of a stated circular orbit (:class:`~formation_ftc.components.estimators.relative_navigation.RelativeNavigationFilter`,
design in :mod:`formation_ftc.design.kalman`). The controller then runs on the filter's estimate
instead of the raw measurement. Every number of the filter is flight knowledge and is stated in the
section: the orbit, the assumed measurement noise, the acceleration noise and the nominal masses.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from pydantic import Field, model_validator

from formation_ftc.components.estimators._fdi import FdiDrift, FdiTest, FdiThreshold
from formation_ftc.config.base import StrictModel
from formation_ftc.core.constants import MU_EARTH
from formation_ftc.methods.composed import (
    BuildContext,
    per_spacecraft,
    register_component_type,
    register_conditions,
)
from formation_ftc.registry import Condition
from formation_ftc.sim.contract import CompositionError, as_float

#: the filter's nominal on-board mass when a scenario states none [kg] (as the PD law's)
NAVIGATION_NOMINAL_MASS = 100.0


class RelativeNavigationSection(StrictModel):
    """Kalman filter of the LVLH relative states (on-board CW model of a circular orbit)."""

    semi_major_axis: float = Field(
        gt=0, description="Radius of the on-board circular reference orbit [m]."
    )
    mu: float = Field(MU_EARTH, gt=0, description="Gravitational parameter [m^3/s^2].")
    position_noise_std: float = Field(
        gt=0, description="Assumed std of the position measurement noise [m]."
    )
    velocity_noise_std: float = Field(
        gt=0, description="Assumed std of the velocity measurement noise [m/s]."
    )
    acceleration_noise_psd: float = Field(
        1e-10,
        ge=0,
        description=(
            "Spectral density of the unmodelled acceleration per axis [(m/s^2)^2/Hz] (J2, drag, "
            "model error, faults the filter does not know)."
        ),
    )
    nominal_mass: float | list[float] = Field(
        NAVIGATION_NOMINAL_MASS,
        description="On-board mass per spacecraft that turns the commanded force into acceleration [kg].",
    )

    def model(self, dt: float):
        """(discrete model, R) of the filter at step ``dt`` [s]."""
        from formation_ftc.core.dynamics.cw import cw_matrices
        from formation_ftc.design.kalman import discrete_model

        n = math.sqrt(self.mu / self.semi_major_axis**3)
        A, B = cw_matrices(n)
        model = discrete_model(A, B, B, self.acceleration_noise_psd, dt)
        R = np.diag([self.position_noise_std**2] * 3 + [self.velocity_noise_std**2] * 3)
        return model, R


def _filter_model(sec: RelativeNavigationSection, ctx: BuildContext, name: str) -> dict:
    """The on-board model's arrays (phi, gamma, qd, r, nominal_mass) at the scenario's step, checked
    against the loop (``name``: the estimator type, for the messages)."""
    from formation_ftc.sim.components import Plant

    if ctx.plant is None or type(ctx.plant).position is Plant.position:
        raise CompositionError(
            f"estimator {name} estimates LVLH relative states, but plant "
            f"{ctx.scenario.type_of('plant')} has none (a translational plant is needed)"
        )
    model, R = sec.model(ctx.dt)
    mass = per_spacecraft(sec.nominal_mass, ctx.count, "estimator.nominal_mass")
    if not np.all(np.isfinite(mass) & (mass > 0)):
        raise CompositionError(f"estimator.nominal_mass: {mass.tolist()} kg, every one must be > 0")
    return dict(
        phi=as_float(model.phi),
        gamma=as_float(model.gamma),
        qd=as_float(model.qd),
        r=as_float(R),
        nominal_mass=as_float(mass),
    )


def _navigation_filter(sec: RelativeNavigationSection, ctx: BuildContext):
    from formation_ftc.components.estimators.relative_navigation import RelativeNavigationFilter

    arrays = _filter_model(sec, ctx, "relative-navigation-filter")
    return RelativeNavigationFilter(count=ctx.count, p0=arrays["r"], **arrays)


register_component_type(
    "estimator",
    "relative-navigation-filter",
    RelativeNavigationSection,
    _navigation_filter,
    "Kalman filter of the LVLH relative states; the controller reads its estimate instead of the "
    "measurement",
)


def _navigation_conditions(scenario, loop) -> list[Condition]:
    """The steady-state filter: Riccati residual, stability of the error dynamics, and the steady-state
    position and velocity standard deviations it promises."""
    from formation_ftc.design.kalman import dare_relative_residual, steady_state_kalman

    sec: RelativeNavigationSection = scenario.section("estimator")
    model, R = sec.model(float(loop.dt))
    P, K = steady_state_kalman(model.phi, model.qd, R)
    residual = dare_relative_residual(P, model.phi, model.qd, R)
    posterior = (np.eye(6) - K) @ P
    rho = float(np.max(np.abs(np.linalg.eigvals(model.phi @ (np.eye(6) - K)))))
    sig = np.sqrt(np.diag(posterior))
    return [
        Condition(
            name="navigation filter: steady-state error dynamics stable",
            reference="design/kalman.py",
            value=f"spectral radius of phi (I - K) = {rho:.6f} (Riccati residual {residual:.1e})",
            requirement="< 1",
            holds=rho < 1.0 - 1e-9 and residual < 1e-8,
            required=True,
            basis="exact",
            detail=(
                "exact: eigenvalues of the estimation-error transition of the steady-state filter, "
                "with the discrete Riccati equation solved to the stated residual"
            ),
        ),
        Condition(
            name="navigation filter: steady-state standard deviation",
            reference="design/kalman.py",
            value=(
                f"position {np.max(sig[:3]):.3g} m, velocity {np.max(sig[3:]):.3g} m/s "
                f"(measurement {sec.position_noise_std:g} m, {sec.velocity_noise_std:g} m/s)"
            ),
            requirement="informative",
            holds=True,
            required=False,
            basis="informative",
            detail="informative: after the measurement update, from the model the filter states",
        ),
    ]


register_conditions("estimator", "relative-navigation-filter", _navigation_conditions)


# ------------------------------------------------------------------------------------------- FDI


class ResidualFdiSection(RelativeNavigationSection):
    """Thruster-fault detection and isolation from the relative-state residuals."""

    residual: Literal["kalman", "parity"] = Field(
        "kalman",
        description="Residual generator: the Kalman innovation or the one-step parity relation.",
    )
    test: FdiTest = "cusum"
    drift: FdiDrift = 0.5
    threshold: FdiThreshold = 20.0
    force_limit: float = Field(
        math.inf,
        gt=0,
        description=(
            "Rated thrust per axis [N] (flight knowledge): a channel whose command reaches it is not "
            "tested over that step (a thrust limit may cut the force, which the residual cannot tell "
            "from a fault); inf: every channel always tested. See at_limit."
        ),
    )
    at_limit: Literal["skip", "clip"] = Field(
        "skip",
        description=(
            "What the residual does at the rated thrust force_limit: skip -- a channel whose command "
            "reaches it is not tested over that step; clip -- the on-board model applies the command "
            "clipped to +-force_limit per axis (what a healthy rated thruster gives) and every channel "
            "is tested, so a fault of a saturated thruster shows too. clip needs a finite force_limit."
        ),
    )

    @model_validator(mode="after")
    def _clip_needs_a_limit(self):
        if self.at_limit == "clip" and not math.isfinite(self.force_limit):
            raise ValueError(
                'at_limit = "clip": give the rated thrust force_limit [N] (finite, > 0) to clip at'
            )
        return self


def _residual_fdi(sec: ResidualFdiSection, ctx: BuildContext):
    from formation_ftc.components.estimators.residual_fdi import ResidualFdi

    a = _filter_model(sec, ctx, "residual-fdi")
    return ResidualFdi(
        count=ctx.count,
        residual=sec.residual,
        test=sec.test,
        parity_cov=as_float(a["r"] + a["phi"] @ a["r"] @ a["phi"].T + a["qd"]),
        drift=as_float(sec.drift),
        threshold=as_float(sec.threshold),
        force_limit=as_float(sec.force_limit),
        at_limit=sec.at_limit,
        **a,
    )


register_component_type(
    "estimator",
    "residual-fdi",
    ResidualFdiSection,
    _residual_fdi,
    "thruster-fault detection and isolation: Kalman or parity residual, CUSUM or fixed threshold",
)


class FdiScoresSection(StrictModel):
    """Truth-side FDI scores (no fields)."""


#: estimator types that record ``fdi_detected`` and ``fdi_isolated`` in the actuator's channels
FDI_ESTIMATORS = ["residual-fdi", "attitude-residual-fdi"]


def _fdi_scores(sec: FdiScoresSection, ctx: BuildContext):
    from formation_ftc.components.evaluations.fdi_scores import FdiScores

    if ctx.scenario.type_of("estimator") not in FDI_ESTIMATORS:
        raise CompositionError(
            "evaluation fdi-scores compares an FDI's alarm with the true fault: it needs [estimator] "
            f"type = {' or '.join(repr(n) for n in FDI_ESTIMATORS)} (the loop has "
            f"{ctx.scenario.type_of('estimator')})"
        )
    if ctx.scenario.type_of("actuator") != "fault-battery":
        raise CompositionError(
            "evaluation fdi-scores reads the true fault of the fault-battery actuator "
            f"(the loop's actuator is {ctx.scenario.type_of('actuator')})"
        )
    return FdiScores()


register_component_type(
    "evaluation",
    "fdi-scores",
    FdiScoresSection,
    _fdi_scores,
    "detection delay, missed detection, false alarm and isolation of an FDI against the true fault",
)


def _fdi_conditions(scenario, loop) -> list[Condition]:
    """The residual model's assumption about the command, and the navigation model's stability."""
    sampled = bool(loop.controller.sampled)
    return [
        Condition(
            name="FDI: command held over each step",
            reference="docs/concepts/navigation-and-fdi.md",
            value=f"controller {scenario.type_of('controller')} "
            + ("is sampled" if sampled else "is evaluated inside the step"),
            requirement="a sampled law (the residual model holds the command over the step)",
            holds=sampled,
            required=False,
            basis="exact",
            detail=(
                "exact: with a law evaluated at every integrator stage the command varies inside the "
                "step, an input the residual does not model (measured on cw-fdi-thruster-bias with the "
                "LQR continuous: 0.36 sigma per step during the acquisition, a false alarm at 12 s)"
            ),
        ),
        *_navigation_conditions(scenario, loop)[:1],
    ]


register_conditions("estimator", "residual-fdi", _fdi_conditions)
