"""Method ``gui2022``: ILO fault reconstruction and LOF2TC / COF2TC formation keeping (Gui et al. 2022).

Plant (1)-(3) on linear CW dynamics, ``q_dot = A q + B u + E d(t) + H F(t)``, ``y = C q`` with
``B = E = H = [0; I3]``, ``C = I6`` (SPEC.md P2.2). One step k (t_k = k dt; SPEC.md P2.4)::

    (1) measure y_k = C q_k
    (3) ILO learning update  F_hat_k = Q1 F_hat_{k-m} + Q2 L2 (y_k - C q_hat_k)         # eq. (5)
    (5) controller           e_k = y0(t_k) - y_k;  pi_k, v_k (31)-(32);  u_k (30)    (or COF2TC / u = 0)
    (7) plant, exact ZOH     q_{k+1} = Ad q_k + Bd (u_k + d(t_k) + F(t_k))          (u, d, F held)
        observer, fwd Euler  q_hat_{k+1} = q_hat_k + dt (A q_hat + B u + H F_hat + L1 e_y + gamma sgn e_y)
    (8) push F_hat_k, pi_k, v_k into their histories; accumulate the metrics that need every step.

The nominal orbit q0(t) (28) is the CW closed form (SPEC.md 0.3) evaluated at t_k (no drift). Fault
onsets are snapped to the step grid. Everything a campaign may vary (n, A0, fault data, gains, initial
states) is in ``params``; the metric windows are step indices in ``params`` too.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
import xarray as xr

from formation_ftc.blocks.controllers.conventional_output_feedback import ConventionalOutputFeedback
from formation_ftc.blocks.controllers.learning_output_feedback import LearningOutputFeedback
from formation_ftc.blocks.observers.iterative_learning_observer import (
    IterativeLearningObserver,
    learning_steps,
    matvec,
)
from formation_ftc.core.dynamics.cw import cw_matrices
from formation_ftc.design.lmi import design_ilo_gains, rescale_design
from formation_ftc.design.riccati import solve_care
from formation_ftc.papers.gui2022.schema import Gui2022Scenario
from formation_ftc.registry import Compiled
from formation_ftc.sim.engine import run_fixed_step

__all__ = ["build", "gains_of", "lmi_design_cached", "care_cached", "cw_a_jnp", "disturbance_jnp",
           "COMPONENTS", "AXES"]

COMPONENTS = ["x", "y", "z", "vx", "vy", "vz"]
AXES = ["x", "y", "z"]


@functools.lru_cache(maxsize=16)
def lmi_design_cached(n: float, lam: float, center: float, radius: float):
    """ILO gains from the LMIs (8), (27), disk S(c, r); cached by input (design/ is offline code)."""
    A, B = cw_matrices(n)
    return design_ilo_gains(A, np.eye(6), B, lam=lam, disk_center=center, disk_radius=radius)


@functools.lru_cache(maxsize=16)
def care_cached(n: float, q_scale: float):
    """CARE (34) with Q = q_scale I6, R = I3; cached."""
    A, B = cw_matrices(n)
    return solve_care(A, B, q_scale * np.eye(6), np.eye(3))


def gains_of(s: Gui2022Scenario) -> dict[str, np.ndarray]:
    """Numeric gains the run uses: L1, L2 (printed or LMI) and K (printed or CARE)."""
    n = s.orbit.mean_motion
    A, B = cw_matrices(n)
    o, c = s.observer, s.controller
    if o.gains == "lmi":
        des = lmi_design_cached(n, o.lmi_lambda, o.disk_center, o.disk_radius)
        if o.lmi_scale != 1.0:
            des = rescale_design(des, o.lmi_scale, A, np.eye(6), B)
        L1, L2 = des.L1, des.L2
    else:
        L1, L2 = np.asarray(o.L1), np.asarray(o.L2)
    K = care_cached(n, c.care_q_scale).K if c.gains == "care" else np.asarray(c.K)
    return {"L1": L1, "L2": L2, "K": K}


def cw_a_jnp(n):
    """CW A(n) as a JAX array (differentiable / vmappable in n)."""
    z = jnp.zeros(())
    n2 = n * n
    rows = [
        [z, z, z, 1.0 + z, z, z],
        [z, z, z, z, 1.0 + z, z],
        [z, z, z, z, z, 1.0 + z],
        [3 * n2, z, z, z, 2 * n, z],
        [z, z, z, -2 * n, z, z],
        [z, z, -n2, z, z, z],
    ]
    return jnp.stack([jnp.stack(r) for r in rows])


def disturbance_jnp(A0, s_nt, c_nt):
    """d(t) = A0 [1 - 1.5 sin nt, 0.5 sin 2nt, sin nt] (ref. [12]) from sin nt, cos nt [m/s^2]."""
    return A0 * jnp.stack([1.0 - 1.5 * s_nt, s_nt * c_nt, s_nt])  # 0.5 sin 2nt = sin nt cos nt


def _closed_form(n, q0, c, s, t):
    """CW closed form (SPEC.md 0.3) at time t from q0, given c = cos nt, s = sin nt."""
    x0, y0, z0, xd, yd, zd = (q0[i] for i in range(6))
    nt = n * t
    return jnp.stack([
        (4 - 3 * c) * x0 + (s / n) * xd + (2 / n) * (1 - c) * yd,
        6 * (s - nt) * x0 + y0 - (2 / n) * (1 - c) * xd + ((4 * s - 3 * nt) / n) * yd,
        c * z0 + (s / n) * zd,
        3 * n * s * x0 + c * xd + 2 * s * yd,
        -6 * n * (1 - c) * x0 - 2 * s * xd + (4 * c - 3) * yd,
        -n * s * z0 + c * zd,
    ])


def _zoh_jnp(A, B, dt):
    """Exact ZOH (Ad, Bd) via expm of [[A, B], [0, 0]] dt (Van Loan), in JAX."""
    n, m = A.shape[0], B.shape[1]
    M = jnp.zeros((n + m, n + m)).at[:n, :n].set(A).at[:n, n:].set(B)
    E = jax.scipy.linalg.expm(M * dt)
    return E[:n, :n], E[:n, n:]


def build(s: Gui2022Scenario) -> Compiled:
    """Compile a gui2022 scenario (see module docstring)."""
    dt = s.simulation.dt
    sim = s.simulation
    law = s.controller.law
    m_obs = learning_steps(s.observer.learning_interval, dt, "observer.learning_interval")
    m_ctl = learning_steps(s.controller.learning_interval, dt, "controller.learning_interval")
    ilo = IterativeLearningObserver(dt=dt, learning_steps=m_obs, sign_term=s.observer.sign_term)
    lof = LearningOutputFeedback(learning_steps=m_ctl)
    cof = ConventionalOutputFeedback(fault_compensation=s.controller.fault_compensation)
    shifted = s.faults.z_decay_shifted
    g = gains_of(s)
    _, B = cw_matrices(s.orbit.mean_motion)
    Bp = np.linalg.pinv(B)  # B^+ = (B^T B)^-1 B^T
    ks = lambda t: int(round(t / dt))  # noqa: E731 - snap a time to the step grid
    f = s.faults
    mt = s.metrics
    onsets = np.array([ks(f.x_onset), ks(f.y_onset), ks(f.z_onset)], dtype=np.int64)
    q_init = np.asarray(s.initial.state, dtype=float)
    params = dict(
        n=jnp.asarray(s.orbit.mean_motion), A0=jnp.asarray(s.disturbance.amplitude),
        onset_k=jnp.asarray(onsets), fx=jnp.asarray(f.x_magnitude), fy=jnp.asarray(f.y_magnitude),
        fz_amp=jnp.asarray(f.z_amplitude), fz_omega=jnp.asarray(f.z_omega), fz_phase=jnp.asarray(f.z_phase),
        fz_dec_amp=jnp.asarray(f.z_decay_amplitude), fz_dec_rate=jnp.asarray(f.z_decay_rate),
        q_init=jnp.asarray(q_init), q_hat_init=jnp.asarray(q_init + np.asarray(s.initial.estimate_offset)),
        q0_init=jnp.asarray(s.initial.desired_state, dtype=jnp.float64),
        L1=jnp.asarray(g["L1"]), L2=jnp.asarray(g["L2"]), Q1=jnp.asarray(s.observer.Q1),
        Q2=jnp.asarray(s.observer.Q2), gamma=jnp.asarray(s.observer.gamma),
        K=jnp.asarray(g["K"]), G1=jnp.asarray(s.controller.G1), G2=jnp.asarray(s.controller.G2),
        G3=jnp.asarray(s.controller.G3), G4=jnp.asarray(s.controller.G4),
        pi_init=jnp.asarray(s.controller.pi_initial), v_init=jnp.asarray(s.controller.v_initial),
        BpE=jnp.asarray(Bp @ B), BpH=jnp.asarray(Bp @ B),
        k_rms=jnp.asarray(onsets + ks(mt.fault_rms_delay)), k_after1=jnp.asarray(onsets + ks(1.0)),
        k_pos=jnp.asarray(ks(mt.position_rms_start)), k_est=jnp.asarray(ks(mt.estimate_start)),
        k_est_end=jnp.asarray(ks(mt.estimate_end)),
        k_zamp=jnp.asarray(ks(mt.z_amplitude_start)), thr=jnp.asarray(mt.settle_threshold),
    )
    track = law != "none"
    rec_every = sim.record_every

    def make_parts(p):
        A = cw_a_jnp(p["n"])
        Bm = jnp.concatenate([jnp.zeros((3, 3)), jnp.eye(3)])
        Ad, Bd = _zoh_jnp(A, Bm, dt)
        pobs = dict(A=A, B=Bm, H=Bm, L1=p["L1"], L2=p["L2"], Q1=p["Q1"], Q2=p["Q2"], gamma=p["gamma"])
        pctl = dict(K=p["K"], G1=p["G1"], G2=p["G2"], G3=p["G3"], G4=p["G4"], BpE=p["BpE"], BpH=p["BpH"])
        return Ad, Bd, pobs, pctl

    def outputs(k, x, p, pobs, pctl):
        """Signals at sample k (shared by step and observe)."""
        t = k * dt
        nt = p["n"] * t
        s_nt, c_nt = jnp.sin(nt), jnp.cos(nt)
        d = disturbance_jnp(p["A0"], s_nt, c_nt)
        on = k >= p["onset_k"]
        t_dec = t - p["onset_k"][2] * dt if shifted else t  # E002-09
        fz = p["fz_amp"] * jnp.sin(p["fz_omega"] * t + p["fz_phase"]) + p["fz_dec_amp"] * jnp.exp(-p["fz_dec_rate"] * t_dec)
        F = jnp.where(on, jnp.stack([p["fx"], p["fy"], fz]), 0.0)
        y = x["q"]  # C = I6: y = C q
        F_hat, e_obs = ilo.learn(pobs, x["obs"], y)
        out = dict(d=d, F=F, F_hat=F_hat, e_obs=e_obs)
        if track:
            q0 = _closed_form(p["n"], p["q0_init"], c_nt, s_nt, t)  # nominal orbit (28)
            e = q0 - y  # e_y = y0 - y (29)
            if law == "lof2tc":
                u, pi, v = lof.control(pctl, x["ctl"], e, F_hat)
            else:
                u, pi, v = cof.control(pctl, e, F_hat), jnp.ones(()), jnp.zeros(3)
            out.update(q0=q0, e=e, u=u, pi=pi, v=v)
        else:
            out.update(u=jnp.zeros(3))
        return out

    def make_step(p, parts=None):
        Ad, Bd, pobs, pctl = parts if parts is not None else make_parts(p)

        def step(k, x):
            o = outputs(k, x, p, pobs, pctl)
            u = o["u"]
            new = dict(x)
            new["q"] = matvec(Ad, x["q"]) + matvec(Bd, u + o["d"] + o["F"])  # exact ZOH, B = E = H
            new["obs"] = ilo.propagate(pobs, x["obs"], u, o["F_hat"], o["e_obs"])
            if law == "lof2tc":
                new["ctl"] = lof.update(x["ctl"], o["pi"], o["v"])
            a = dict(x["acc"])
            # mean of F_hat over the current record interval: with the sign term F_hat chatters with period
            # 2 steps (+-4.2e-4 before the faults), which decimated samples would alias into an offset
            a["Fh_sum"] = jnp.where(k % rec_every == 0, 0.0, a["Fh_sum"]) + o["F_hat"]
            ef = o["F"] - o["F_hat"]
            aef = jnp.abs(ef)
            w = k >= p["k_rms"]
            a["ef_sq"] = a["ef_sq"] + jnp.where(w, ef * ef, 0.0)
            a["ef_n"] = a["ef_n"] + w
            a["sgn_sum"] = a["sgn_sum"] + jnp.where(jnp.concatenate([w, w]), jnp.sign(o["e_obs"]), 0.0)
            a["settle_k"] = jnp.where((k >= p["onset_k"]) & (aef > p["thr"]), k, a["settle_k"])
            a["ef_max1"] = jnp.where(k >= p["k_after1"], jnp.maximum(a["ef_max1"], aef), a["ef_max1"])
            ey = jnp.sqrt(o["e_obs"] @ o["e_obs"])
            a["ey_max"] = jnp.where((k >= p["k_est"]) & (k < p["k_est_end"]), jnp.maximum(a["ey_max"], ey),
                                    a["ey_max"])
            if track:
                ep = o["e"][:3]
                epn = jnp.sqrt(ep @ ep)
                wp = k >= p["k_pos"]
                a["pos_sq"] = a["pos_sq"] + jnp.where(wp, epn * epn, 0.0)
                a["pos_n"] = a["pos_n"] + wp
                kx, kz = p["onset_k"][0], p["onset_k"][2]
                a["pos_max_fault"] = jnp.where(k >= kx, jnp.maximum(a["pos_max_fault"], epn), a["pos_max_fault"])
                a["ex_max_window"] = jnp.where((k >= kx) & (k < kz), jnp.maximum(a["ex_max_window"], jnp.abs(ep[0])),
                                               a["ex_max_window"])
                a["ez_max_after"] = jnp.where(k >= p["k_zamp"], jnp.maximum(a["ez_max_after"], jnp.abs(ep[2])),
                                              a["ez_max_after"])
                a["pos_settle_k"] = jnp.where(epn > 0.01, k, a["pos_settle_k"])
                a["pi_max"] = jnp.maximum(a["pi_max"], o["pi"])
            new["acc"] = a
            return new

        return step

    def observe(k, x, p, parts):
        _, _, pobs, pctl = parts
        o = outputs(k, x, p, pobs, pctl)
        F_hat_mean = jnp.where(k == 0, o["F_hat"], x["acc"]["Fh_sum"] / rec_every)
        rec = dict(q=x["q"], q_hat=x["obs"].q_hat, F=o["F"], F_hat=o["F_hat"], F_hat_mean=F_hat_mean, d=o["d"],
                   u=o["u"])
        if track:
            rec.update(q0=o["q0"], pi=o["pi"], v=o["v"])
        return rec

    def initial_state(p):
        acc = dict(Fh_sum=jnp.zeros(3), ef_sq=jnp.zeros(3), ef_n=jnp.zeros(3), sgn_sum=jnp.zeros(6),
                   settle_k=-jnp.ones(3, dtype=jnp.int64), ef_max1=jnp.zeros(3), ey_max=jnp.zeros(()))
        if track:
            acc.update(pos_sq=jnp.zeros(()), pos_n=jnp.zeros(()), pos_max_fault=jnp.zeros(()),
                       ex_max_window=jnp.zeros(()), ez_max_after=jnp.zeros(()),
                       pos_settle_k=-jnp.ones((), dtype=jnp.int64), pi_max=jnp.zeros(()))
        x = dict(q=p["q_init"], obs=ilo.init(p["q_hat_init"], jnp.zeros(3)), acc=acc)
        if law == "lof2tc":
            x["ctl"] = lof.init(p["pi_init"], p["v_init"])
        return x

    def run(p):
        parts = make_parts(p)  # ZOH and gain matrices once per run, outside the scan
        return run_fixed_step(make_step(p, parts), lambda k, x: observe(k, x, p, parts), initial_state(p),
                              sim.n_steps, sim.record_every, sim.unroll)

    def to_dataset(out, n_rec):
        r = out["records"]
        time = np.arange(n_rec) * dt * sim.record_every
        dims_c, dims_a = ("time", "component"), ("time", "axis")
        v = {
            "state": (dims_c, r["q"], {"units": "m, m/s", "frame": "LVLH", "long_name": "deputy relative state q"}),
            "estimate": (dims_c, r["q_hat"], {"units": "m, m/s", "long_name": "ILO state estimate q_hat"}),
            "estimation_error": (dims_c, r["q"] - r["q_hat"], {"units": "m, m/s", "long_name": "e_q = q - q_hat"}),
            "fault": (dims_a, r["F"], {"units": "m/s^2", "long_name": "thruster bias fault F"}),
            "fault_estimate": (dims_a, r["F_hat"], {"units": "m/s^2", "long_name": "reconstructed fault F_hat"}),
            "fault_error": (dims_a, r["F"] - r["F_hat"], {"units": "m/s^2", "long_name": "e_F = F - F_hat"}),
            "disturbance": (dims_a, r["d"], {"units": "m/s^2", "long_name": "space perturbation d"}),
            "control": (dims_a, r["u"], {"units": "m/s^2", "long_name": "commanded acceleration u"}),
            "synthesized_disturbance": (dims_a, r["d"] + r["F"] - r["F_hat"],
                                        {"units": "m/s^2", "long_name": "h = d + e_F (33)"}),
            "fault_estimate_mean": (dims_a, r["F_hat_mean"], {
                "units": "m/s^2", "long_name": "F_hat averaged over the record interval (removes the "
                                               "period-2-step chatter caused by the sign term)"}),
            "synthesized_disturbance_mean": (dims_a, r["d"] + r["F"] - r["F_hat_mean"], {
                "units": "m/s^2", "long_name": "h = d + F - mean(F_hat) over the record interval"}),
        }
        if track:
            v["desired_state"] = (dims_c, r["q0"], {"units": "m, m/s", "long_name": "nominal orbit q0 (28)"})
            v["tracking_error"] = (dims_c, r["q0"] - r["q"], {"units": "m, m/s", "long_name": "e_q = q0 - q (29)"})
            v["learning_gain"] = (("time",), r["pi"], {"units": "-", "long_name": "pi (31)"})
            v["compensation"] = (dims_a, r["v"], {"units": "m/s^2", "long_name": "v (32)"})
        return xr.Dataset(v, coords={"time": ("time", time, {"units": "s"}), "component": COMPONENTS,
                                     "axis": AXES})

    def metrics(out):
        a = {k: np.asarray(v) for k, v in out["final"]["acc"].items()}
        fin = out["final"]
        m: dict[str, float] = {}
        for i, ax in enumerate(AXES):
            m[f"fault_rms_err_{ax}"] = float(np.sqrt(a["ef_sq"][i] / a["ef_n"][i])) if a["ef_n"][i] else float("nan")
            sk = int(a["settle_k"][i])
            m[f"fault_settle_time_{ax}"] = float((sk + 1 - onsets[i]) * dt) if sk >= 0 else 0.0
            m[f"fault_max_err_after_1s_{ax}"] = float(a["ef_max1"][i])
        for i, c in enumerate(COMPONENTS):
            ax_i = i % 3
            m[f"sign_mean_{c}"] = float(a["sgn_sum"][i] / a["ef_n"][ax_i]) if a["ef_n"][ax_i] else float("nan")
        m["estimate_max_err_after_start"] = float(a["ey_max"])
        # final values (state after the last step; F_hat of the last record)
        r = out["records"]
        ef_last = np.asarray(r["F"])[-1] - np.asarray(r["F_hat"])[-1]
        for i, ax in enumerate(AXES):
            m[f"final_fault_err_{ax}"] = float(ef_last[i])
        if track:
            m["pos_rms"] = float(np.sqrt(a["pos_sq"] / a["pos_n"])) if a["pos_n"] else float("nan")
            m["pos_max_after_fault"] = float(a["pos_max_fault"])
            m["ex_max_fault_window"] = float(a["ex_max_window"])
            m["ez_max_after"] = float(a["ez_max_after"])
            m["pos_settle_time_0p01"] = float((int(a["pos_settle_k"]) + 1) * dt)
            m["pi_max"] = float(a["pi_max"])
            e_last = np.asarray(r["q0"])[-1] - np.asarray(fin["q"])
            m["final_pos_err"] = float(np.linalg.norm(e_last[:3]))
            m["final_vel_err"] = float(np.linalg.norm(e_last[3:]))
        return m

    key = ("gui2022", law, m_obs, m_ctl, s.observer.sign_term, s.controller.fault_compensation, shifted,
           sim.n_steps, sim.record_every, dt, sim.unroll)
    return Compiled(run=run, params=params, static_key=key, dt=dt, record_every=sim.record_every,
                    to_dataset=to_dataset, metrics=metrics, make_step=make_step,
                    spacecraft_axis=lambda name: None)
