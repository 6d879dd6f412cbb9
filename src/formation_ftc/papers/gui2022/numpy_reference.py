"""Plain-numpy, per-step Python loop of the gui2022 closed loop (independent reference).

Written directly from the paper's equations (with the choices of E002-10) without the JAX blocks, the history ring
buffer or the engine: used by the tests (agreement with the JAX scan) and by ``benchmarks/gui2022.py``
(speed ratio). Slow by design (~10-20 us/step); use short horizons. It reads the numbers of a composed
``gui2022-*`` scenario (one deputy: plant ``clohessy-wiltshire-zoh``, the ILO, ``free-drift`` or a
Gui2022 law, ``thruster-bias`` faults).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg

from formation_ftc.components.controllers._output_feedback import (
    OutputFeedbackSection,
    care_solution,
)
from formation_ftc.components.controllers.gui2022_lof2tc import Lof2tcSection
from formation_ftc.core.dynamics.cw import cw_matrices, cw_state_transition
from formation_ftc.methods.composed import ComposedScenario
from formation_ftc.papers.gui2022.conditions import onboard_n

__all__ = ["simulate_numpy"]


def _axes(value) -> np.ndarray:
    """A thruster-bias field (one number, 3 values or one row of 3) -> (3,) of the deputy."""
    return np.broadcast_to(np.asarray(value, float), (1, 3))[0]


def simulate_numpy(s: ComposedScenario, n_steps: int | None = None) -> dict[str, np.ndarray]:
    """Run ``n_steps`` (default horizon/dt) steps; returns per-step arrays (index k = sample k, F_hat_k,
    u_k ...) and the states q, q_hat at k = 0..n_steps."""
    dt = s.simulation.dt
    N = s.simulation.n_steps if n_steps is None else n_steps
    p, o, c, f = (s.section(slot) for slot in ("plant", "estimator", "controller", "actuator"))
    tracks, learns = isinstance(c, OutputFeedbackSection), isinstance(c, Lof2tcSection)
    n = p.mean_motion  # truth [rad/s]
    A, B = cw_matrices(n)
    M = np.zeros((9, 9))
    M[:6, :6], M[:6, 6:] = A, B
    E = scipy.linalg.expm(M * dt)
    Ad, Bd = E[:6, :6], E[:6, 6:]
    n_o = onboard_n(o.mean_motion, s)
    A_o, B_o = cw_matrices(n_o)
    L1, L2 = o.gains_at(n_o)
    Q1, Q2, gam = np.asarray(o.Q1), o.Q2, (o.gamma if o.sign_term else 0.0)
    m_o = round(o.learning_interval / dt)
    onset = [round(t / dt) for t in _axes(f.onset)]
    mag, amp, om, ph = (_axes(v) for v in (f.magnitude, f.amplitude, f.omega, f.phase))
    dec, rate, origin = (_axes(v) for v in (f.decay_amplitude, f.decay_rate, f.decay_origin))
    A0 = p.disturbance_amplitude
    v0 = [0.0] * 3 if p.initial_velocity is None else p.initial_velocity[0]
    q = np.concatenate([p.initial_position[0], v0]).astype(float)
    qh = np.asarray(o.initial_estimate, float).reshape(-1, 6)[0].copy()
    if tracks:
        n_c = onboard_n(c.mean_motion, s)
        K = np.asarray(c.K, float) if c.gains == "printed" else care_solution(n_c, c.care_q_scale).K
        q00 = np.asarray(c.desired_state[0], float)
    m_c = round(c.learning_interval / dt) if learns else 1
    F_hist = [np.zeros(3)] * m_o  # F_hat_{k-m} ... F_hat_{k-1}
    pi_hist = [c.pi_initial if learns else 1.0] * m_c
    v_hist = [np.asarray(c.v_initial if learns else (0.0,) * 3, float)] * m_c
    out: dict[str, np.ndarray] = {k: np.zeros((N, 3)) for k in ("F", "F_hat", "u", "d", "v")}
    out |= {"pi": np.zeros(N), "q": np.zeros((N + 1, 6)), "q_hat": np.zeros((N + 1, 6))}
    out["q"][0], out["q_hat"][0] = q, qh
    for k in range(N):
        t = k * dt
        d = A0 * np.array([1 - 1.5 * math.sin(n * t), 0.5 * math.sin(2 * n * t), math.sin(n * t)])
        F = np.array(
            [
                mag[i]
                + amp[i] * math.sin(om[i] * t + ph[i])
                + dec[i] * math.exp(-rate[i] * (t - origin[i]))
                if k >= onset[i]
                else 0.0
                for i in range(3)
            ]
        )
        y = q.copy()
        ey = y - qh
        F_hat = Q1 * F_hist[0] + Q2 * (L2 @ ey)  # (5)
        pi, v = 1.0, np.zeros(3)
        if not tracks:
            u = np.zeros(3)
        else:
            e = cw_state_transition(n_c, t) @ q00 - y
            Ke = K @ e
            if learns:
                pi = c.G1 * pi_hist[0] + c.G2 * float(Ke @ Ke)  # (31)
                v = np.asarray(c.G3) * v_hist[0] + c.G4 * Ke  # (32)
                u = pi * Ke - v - F_hat  # (30), B+E = B+H = I3
            else:
                u = Ke - (F_hat if c.fault_compensation else 0.0)
        q = Ad @ q + Bd @ (u + d + F)
        qh = qh + dt * (A_o @ qh + B_o @ u + B_o @ F_hat + L1 @ ey + gam * np.sign(ey))
        F_hist = F_hist[1:] + [F_hat]
        pi_hist = pi_hist[1:] + [pi]
        v_hist = v_hist[1:] + [v]
        for key, value in dict(F=F, F_hat=F_hat, u=u, d=d, v=v, pi=pi).items():
            out[key][k] = value
        out["q"][k + 1], out["q_hat"][k + 1] = q, qh
    return out
