"""LQR formation keeping on the Clohessy-Wiltshire model: a non-fault-tolerant baseline.

Reads only :class:`~formation_ftc.sim.components.FlightInputs` (the measured relative state); no
communication, no fault estimate, no adaptation.
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp

from formation_ftc.components.controllers.pd_formation import DesiredPositionLaw
from formation_ftc.core.dynamics.cw import cw_rhs
from formation_ftc.sim.components import FlightInputs, component

__all__ = ["LqrFormationController"]


@component
class LqrFormationController(DesiredPositionLaw):
    """LQR state feedback with the feed-forward that makes the desired state a CW equilibrium [N]::

        u_i = m_i ( -K (q_i - q_i^d) - (A q_i^d)[3:] + a_i^d )        (1)

    q_i = [p_i, v_i] is the measured LVLH state [m, m/s], q_i^d = [p_i^d(t), v_i^d(t)] the desired one
    and a_i^d(t) its acceleration (expressions as in
    :class:`~formation_ftc.components.controllers.pd_formation.DesiredPositionLaw`); A is the CW matrix
    of the on-board mean motion. On the CW model, (1) gives the error dynamics
    ``e_dot = (A - B K) e`` with ``e = q - q^d`` (the feed-forward cancels ``A q^d - q_dot^d``).

    ``gain`` K (3, 6) [1/s^2 | 1/s] is designed before the run (e.g. by
    :func:`formation_ftc.design.lqr.cw_lqr`); a campaign that varies ``mean_motion`` does not redesign it.
    ``mass`` (N,) is the nominal on-board mass [kg]; ``mean_motion`` n [rad/s] of the on-board model.
    """

    gain: Any = None  # (3, 6) K [1/s^2 | 1/s]
    mass: Any = 1.0  # (N,) nominal masses [kg]
    mean_motion: Any = 0.0  # on-board n [rad/s]

    def output(self, t, state, inputs: FlightInputs):
        y, d = inputs.measurement, inputs.exogenous
        qd = jnp.concatenate([d["p"], d["v"]], axis=-1)  # (N, 6)
        # (A q^d)[3:]: the CW accelerations of the desired state with no input
        drift = cw_rhs(t, qd, jnp.zeros_like(d["a"]), self.mean_motion)[:, 3:]
        accel = -(y - qd) @ jnp.transpose(self.gain) - drift + d["a"]  # eq. (1) / m_i
        return self.mass[:, None] * accel, None, {}
