"""Output-feedback formation keeping on a nominal CW orbit: LOF2TC (Gui et al. 2022 (30)-(32)), the
fixed-gain COF2TC baseline, and free drift. Each reads only :class:`~formation_ftc.sim.components.FlightInputs`:
the measured (N, 6) relative state, the fault estimate of an estimator (``estimate["fault"]``, zero
without one) and its own time signal, the nominal orbit."""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp

from formation_ftc.blocks.controllers.conventional_output_feedback import cof2tc_law
from formation_ftc.blocks.controllers.learning_output_feedback import lof2tc_law
from formation_ftc.core.delay_line import delay_init, delay_push, delay_read
from formation_ftc.core.dynamics.cw import cw_free_motion
from formation_ftc.sim.components import Controller, FlightInputs, Signal, component, static

__all__ = [
    "NominalOrbitTracking",
    "LearningOutputFeedbackController",
    "ConventionalOutputFeedbackController",
]

STATE = ("spacecraft", "component")
VEC = ("spacecraft", "axis")


@component
class NominalOrbitTracking(Controller):
    """Base of the sampled output-feedback laws: the nominal orbit q0(t) = Phi(t) q0(0) of the CW free
    motion (28) (mean motion ``mean_motion`` [rad/s], ``desired_initial`` (N, 6) [m, m/s]) as the
    controller's own time signal, and the tracking error e_y = y0 - y = q0 - y (29) with C = I6.
    ``hold_desired``: q0(t) = q0(0) held fixed instead (slots fixed in LVLH, which are not free CW motion
    unless purely along-track: the force that holds them is then, for the law, an unmodelled
    disturbance)."""

    quantity = "acceleration"

    count: int = static()
    mean_motion: Any = 0.0  # [rad/s]
    desired_initial: Any = 0.0  # q0(0), (N, 6) [m, m/s]
    hold_desired: bool = static(default=False)

    @property
    def sampled(self) -> bool:
        return True  # u_k held over the step (zero-order hold)

    def exogenous(self, t):
        if self.hold_desired:
            return {
                "q0": self.desired_initial + 0.0 * t
            }  # fixed slots (same shape and dtype as (28))
        return {"q0": cw_free_motion(self.mean_motion, self.desired_initial, t)}  # (28)

    def desired_position_at(self, exogenous):
        return exogenous["q0"][:, :3]

    def tracking(self, inputs: FlightInputs):
        """(q0, e_y, F_hat) from the flight inputs."""
        q0 = inputs.exogenous["q0"]
        F_hat = jnp.zeros((self.count, 3)) if inputs.estimate is None else inputs.estimate["fault"]
        return q0, q0 - inputs.measurement, F_hat  # (29)

    def signals(self):
        return (
            Signal(
                "desired_state",
                STATE,
                "m, m s-1",
                "nominal orbit q0 (28) (positions [m], velocities [m s-1])",
                "LVLH",
            ),
            Signal(
                "tracking_error",
                STATE,
                "m, m s-1",
                "measured tracking error e_y = q0 - y (29)",
                "LVLH",
            ),
        )

    def output(self, t, state, inputs):  # pragma: no cover - subclasses define the law
        raise NotImplementedError


@component
class LearningOutputFeedbackController(NominalOrbitTracking):
    """LOF2TC (30)-(32) per spacecraft::

        pi_k = G1 pi_{k-m} + G2 |K e_y|^2,   v_k = G3 v_{k-m} + G4 K e_y,
        u_k  = pi_k K e_y - B^+E v_k - B^+H F_hat_k                                [m/s^2]

    Gains K (3, 6) [1/s^2, 1/s], G1 [-], G2 [s^4/m^2], G3 (3,) [-], G4 [-], BpE = B^+ E and BpH = B^+ H
    (3, 3); learning interval tau = m dt (``learning_steps``); prehistories ``pi_initial`` (N,) [-] and
    ``v_initial`` (N, 3) [m/s^2] (E002-08). State: the delay lines of pi and v."""

    K: Any = 0.0
    G1: Any = 0.0
    G2: Any = 0.0
    G3: Any = 0.0
    G4: Any = 0.0
    BpE: Any = 0.0
    BpH: Any = 0.0
    pi_initial: Any = 1.0  # (N,)
    v_initial: Any = 0.0  # (N, 3)
    learning_steps: int = static(default=1)

    def initial_state(self):
        m = self.learning_steps
        return {"pi": delay_init(self.pi_initial, m), "v": delay_init(self.v_initial, m)}

    def output(self, t, state, inputs: FlightInputs):
        m = self.learning_steps
        q0, e_y, F_hat = self.tracking(inputs)
        u, pi, v = lof2tc_law(
            e_y,
            F_hat,
            delay_read(state["pi"], m),
            delay_read(state["v"], m),
            self.K,
            self.G1,
            self.G2,
            self.G3,
            self.G4,
            self.BpE,
            self.BpH,
        )  # (30)-(32)
        nxt = {"pi": delay_push(state["pi"], pi, m), "v": delay_push(state["v"], v, m)}
        return (
            u,
            nxt,
            {"desired_state": q0, "tracking_error": e_y, "learning_gain": pi, "compensation": v},
        )

    def signals(self):
        return super().signals() + (
            Signal("learning_gain", ("spacecraft",), "1", "learning gain pi (31)"),
            Signal("compensation", VEC, "m s-2", "learning compensation v (32)", "LVLH"),
        )


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
