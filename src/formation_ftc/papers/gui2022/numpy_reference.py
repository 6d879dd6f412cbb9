"""Plain-numpy, per-step Python loop of the gui2022 closed loop (independent reference).

Written directly from the paper's equations (with the choices of E002-10) without the JAX blocks, the history ring
buffer or the engine: used by the tests (agreement with the JAX scan) and by ``benchmarks/gui2022.py``
(speed ratio). Slow by design (~10-20 us/step); use short horizons.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg

from formation_ftc.core.dynamics.cw import cw_matrices, cw_state_transition
from formation_ftc.papers.gui2022.conditions import gains_of
from formation_ftc.papers.gui2022.schema import Gui2022Scenario

__all__ = ["simulate_numpy"]


def simulate_numpy(s: Gui2022Scenario, n_steps: int | None = None) -> dict[str, np.ndarray]:
    """Run ``n_steps`` (default horizon/dt) steps; returns per-step arrays (index k = sample k, F_hat_k,
    u_k ...) and the states q, q_hat at k = 0..n_steps."""
    dt = s.simulation.dt
    N = s.simulation.n_steps if n_steps is None else n_steps
    n = s.orbit.mean_motion
    A, B = cw_matrices(n)
    M = np.zeros((9, 9))
    M[:6, :6], M[:6, 6:] = A, B
    E = scipy.linalg.expm(M * dt)
    Ad, Bd = E[:6, :6], E[:6, 6:]
    g = gains_of(s)
    L1, L2, K = g["L1"], g["L2"], g["K"]
    o, c, f = s.observer, s.controller, s.faults
    Q1, Q2, gam = np.asarray(o.Q1), o.Q2, (o.gamma if o.sign_term else 0.0)
    m_o = round(o.learning_interval / dt)
    m_c = round(c.learning_interval / dt)
    kx, ky, kz = (round(t / dt) for t in (f.x_onset, f.y_onset, f.z_onset))
    A0 = s.disturbance.amplitude
    q = np.asarray(s.initial.state, float).copy()
    qh = np.asarray(s.observer.initial_estimate, float).copy()
    q00 = np.asarray(s.initial.desired_state, float)
    F_hist = [np.zeros(3)] * m_o  # F_hat_{k-m} ... F_hat_{k-1}
    pi_hist = [c.pi_initial] * m_c
    v_hist = [np.asarray(c.v_initial, float)] * m_c
    out: dict[str, np.ndarray] = {k: np.zeros((N, 3)) for k in ("F", "F_hat", "u", "d", "v")}
    out["pi"] = np.zeros(N)
    out["q"] = np.zeros((N + 1, 6))
    out["q_hat"] = np.zeros((N + 1, 6))
    out["q"][0], out["q_hat"][0] = q, qh
    for k in range(N):
        t = k * dt
        d = A0 * np.array([1 - 1.5 * math.sin(n * t), 0.5 * math.sin(2 * n * t), math.sin(n * t)])
        t_dec = t - kz * dt if f.z_decay_shifted else t
        Fz = f.z_amplitude * math.sin(f.z_omega * t + f.z_phase) + f.z_decay_amplitude * math.exp(
            -f.z_decay_rate * t_dec
        )
        F = np.array(
            [
                f.x_magnitude if k >= kx else 0.0,
                f.y_magnitude if k >= ky else 0.0,
                Fz if k >= kz else 0.0,
            ]
        )
        y = q.copy()
        ey = y - qh
        F_hat = Q1 * F_hist[0] + Q2 * (L2 @ ey)  # (5)
        pi, v = 1.0, np.zeros(3)
        if c.law == "none":
            u = np.zeros(3)
        else:
            e = cw_state_transition(n, t) @ q00 - y
            Ke = K @ e
            if c.law == "lof2tc":
                pi = c.G1 * pi_hist[0] + c.G2 * float(Ke @ Ke)  # (31)
                v = np.asarray(c.G3) * v_hist[0] + c.G4 * Ke  # (32)
                u = pi * Ke - v - F_hat  # (30), B+E = B+H = I3
            else:
                u = Ke - (F_hat if c.fault_compensation else 0.0)
        q = Ad @ q + Bd @ (u + d + F)
        qh = qh + dt * (A @ qh + B @ u + B @ F_hat + L1 @ ey + gam * np.sign(ey))
        F_hist = F_hist[1:] + [F_hat]
        pi_hist = pi_hist[1:] + [pi]
        v_hist = v_hist[1:] + [v]
        out["F"][k], out["F_hat"][k], out["u"][k], out["d"][k], out["v"][k], out["pi"][k] = (
            F,
            F_hat,
            u,
            d,
            v,
            pi,
        )
        out["q"][k + 1], out["q_hat"][k + 1] = q, qh
    return out
