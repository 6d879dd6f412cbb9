"""Relative-output formation control on a chain with LLFR control allocation whose weights the HL
supervisor's mode selects (Azizi & Khorasani 2009, Sec. II, eq. (3))."""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np

from formation_ftc.blocks.controllers.azizi2009_llfr import (
    allocate,
    mode_allocation_matrices,
    relative_output_law,
)
from formation_ftc.blocks.supervisors.hierarchical_supervisor import LLFR
from formation_ftc.core.polygon_formation import chain_difference, rotating_polygon
from formation_ftc.sim.components import Controller, FlightInputs, Signal, component, static

__all__ = ["ChainLlfrController", "ChainLlfrOnBoardController"]

VEC = ("spacecraft", "axis")


@component
class ChainLlfrController(Controller):
    """Formation keeping of a rotating regular polygon on the chain of relative outputs::

        e_ij = y_ij - (x_j^d - x_i^d),   e'_ij likewise from the measured relative velocities
        p_ij = xdd_ij^d - lambda1 e'_ij - lambda0 e_ij                               (Sec. II)
        u    = M(alpha_mode, b_hat_mode) p                                           (eq. (3))

    reading the :class:`~formation_ftc.components.sensors.chain_relative.ChainRelativeSensors`
    measurement (``"position"``/``"velocity"``, (N-1, axes)). The decision of the HL supervisor (an
    integer mode: 0 Nominal, 1 LLFR, 2 FLFR) selects the allocation: Nominal (alpha, b_nominal), LLFR
    (alpha, b_hat), FLFR (alpha with alpha_k = ``alpha_flfr`` for satellite ``fault_index``, b_hat).
    Without a supervisor (no decision) the LLFR allocation is used. The three matrices per axis are
    computed once per run (controller state). Desired formation: regular polygon of side ``side``
    [m] rotating at ``omega`` [rad/s] (:func:`formation_ftc.core.polygon_formation.rotating_polygon`).
    ``is_sampled``: u computed at t_k and held over the step; otherwise re-evaluated at every RK stage.
    Command u [m/s^2 per unit actuator gain].
    """

    lambda0: Any  # [1/s^2]
    lambda1: Any  # [1/s]
    alpha: Any  # (N,) allocation weights [-]
    alpha_flfr: Any  # FLFR weight of satellite fault_index [-]
    b_nominal: Any  # (N, axes) nominal actuator gains [-]
    b_hat: Any  # (N, axes) estimated actuator gains (LLFR) [-]
    side: Any  # [m]
    omega: Any  # [rad/s]
    fault_index: int = static(default=0)  # 0-based satellite whose weight FLFR raises
    is_sampled: bool = static(default=True)
    frame: str = static(default="inertial")  # frame of the desired formation's axes (records only)

    @property
    def sampled(self) -> bool:
        return self.is_sampled

    @property
    def count(self) -> int:
        return int(np.shape(self.b_hat)[0])

    @property
    def n_axes(self) -> int:
        return int(np.shape(self.b_hat)[1])

    quantity = "acceleration"

    def desired(self, t):
        """Desired positions, velocities, accelerations (N, axes) at ``t`` [s]."""
        return rotating_polygon(t, self.count, self.n_axes, self.side, self.omega)

    def initial_state(self):
        return {
            "allocation": mode_allocation_matrices(
                self.alpha, self.alpha_flfr, self.fault_index, self.b_nominal, self.b_hat
            )
        }

    def output(self, t, state, inputs: FlightInputs):
        rd, vd, ad = self.desired(t)
        y = inputs.measurement
        e = y["position"] - chain_difference(rd)
        e_dot = y["velocity"] - chain_difference(vd)
        p = relative_output_law(
            e, e_dot, chain_difference(ad), self.lambda0, self.lambda1
        )  # Sec. II
        mode = LLFR if inputs.decision is None else inputs.decision
        u = allocate(state["allocation"][mode], p)  # eq. (3)
        if self.sampled:
            nxt = state
        else:  # the matrices are constant: zero derivative
            nxt = {"allocation": jnp.zeros_like(state["allocation"])}
        return u, nxt, {"desired_position": rd}

    def signals(self):
        return (
            Signal(
                "desired_position",
                VEC,
                "m",
                "desired position of the rotating formation",
                self.frame,
            ),
        )

    def coords(self):
        return {"pair": [f"{j + 1}-{j + 2}" for j in range(self.count - 1)]}


@component
class ChainLlfrOnBoardController(ChainLlfrController):  # type: ignore[misc]  # fields inherited as declared
    """:class:`ChainLlfrController` reading the
    (N, 6) LVLH relative-state measurement (``lvlh-relative-state`` sensors): the chain outputs are
    formed on board from it, ``y_ij = q_{i+1} - q_i`` on the first ``n_axes`` position and velocity
    axes (the same law; the noise of a chain output is that of two spacecraft's states)."""

    def output(self, t, state, inputs: FlightInputs):
        q = inputs.measurement
        na = self.n_axes
        y = {
            "position": chain_difference(q[:, :na]),
            "velocity": chain_difference(q[:, 3 : 3 + na]),
        }
        return ChainLlfrController.output(self, t, state, inputs._replace(measurement=y))
