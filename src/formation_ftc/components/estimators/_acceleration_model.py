"""An estimator whose internal model is driven by accelerations, in a loop whose command is a force
(what it needs and provides is the inner estimator's)."""

from __future__ import annotations

from typing import Any

import numpy as np

from formation_ftc.components._pass_through import PassThrough
from formation_ftc.components._sections import check_nominal_masses
from formation_ftc.sim.components import Estimator, FlightInputs, component

__all__ = ["AccelerationModelEstimator", "WrapsInner"]


class WrapsInner(PassThrough, Estimator):  # type: ignore[override]  # a property holds_exogenous
    """An estimator built around another one (its field ``inner``), passing through unchanged the
    spacecraft count, the inner estimator's time signals, coordinates and conditions."""

    inner: Estimator


@component
class AccelerationModelEstimator(WrapsInner):
    """Runs ``inner`` (an estimator whose model takes the command as an acceleration [m/s^2], e.g. the
    iterative learning observer's CW model ``q_hat' = A q_hat + B u + ...``) in a loop whose controller
    commands forces [N] (a force-driven plant). The time update receives the command per unit of the
    flight side's nominal mass::

        u_i = f_i / m_i^nom                                                         [m/s^2]

    ``nominal_mass`` (N,) [kg] is the on-board value (the same one that turned the law's acceleration
    into the force, so u_i is exactly the law's acceleration command). With a true mass m_i != m_i^nom
    the plant receives (m_i^nom / m_i) u_i: the difference is part of what the estimator sees as an
    unknown input. Everything else (update, state, estimate, recorded signals) is ``inner``'s.
    """

    inner: Estimator
    nominal_mass: Any  # (N,) [kg]

    def __post_init__(self) -> None:
        m = self.nominal_mass
        if not isinstance(self.inner, Estimator) or not isinstance(m, np.ndarray):
            return  # pytree reconstruction with placeholders
        check_nominal_masses(
            m,
            getattr(self.inner, "count", None),
            "AccelerationModelEstimator",
            f"estimator {type(self.inner).__name__}",
            "need one finite mass > 0 each",
        )

    def initial_state(self, measurement0):
        return self.inner.initial_state(measurement0)

    def update(self, t, state, inputs: FlightInputs):
        return self.inner.update(t, state, inputs)

    def predict(self, t, state, command, dt):
        # u_i = f_i / m_i^nom
        return self.inner.predict(t, state, command / self.nominal_mass[:, None], dt)

    def signals(self):
        return self.inner.signals()

    def outputs(self, t, state, estimate):
        return self.inner.outputs(t, state, estimate)

    def needs(self) -> dict[str, str]:
        return self.inner.needs()

    def provides(self) -> frozenset[str]:
        return self.inner.provides()
