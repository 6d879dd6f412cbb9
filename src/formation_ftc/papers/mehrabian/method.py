"""Method ``mehrabian``: m spacecraft attitudes as networked EL systems (Mehrabian et al. (1)-(2), (27)-(28))
under the distributed H-infinity law (6)/(8) with adaptive fault recovery (18)-(19) fed by an imperfect
FDI (:mod:`formation_ftc.blocks.fdi`).

One step k (t = k dt; ARCHITECTURE.md "One control step"):

1. truth side: additive fault u_bar(t_k) (snapped windows) and Gaussian disturbance d_k ~ N(0, var I)
   with key fold_in(dist_key, k), both held over the step;
2. FDI: flag and estimate u*(t_k) (detection latency, identification / isolation errors);
3. RK4 over [t_k, t_k + dt]: at every stage the controller (6)+(8)+(18) is evaluated from the measured
   (q, q_dot) and its states (z = int q~, u^), the adaptive law (19) and z are integrated with the
   plant, the plant is the rigid body J w_dot = -w x Jw + R_bar^T (u + u_bar + d) with the true J;
4. metric accumulators: integrals (RK) of the mean squared sync error over neighbour pairs, the mean
   squared tracking error and sum |u|^2, and running maxima, for each metric window.

Randomness (documented choice): everything random is drawn **inside the run** from the integer
``params["seed"]``: ``run_key(seed)`` is split into (initial attitudes, inertia perturbation,
disturbance, FDI noise); per-step keys are ``fold_in(key, k)``. A campaign varies the seed through
params (vmap over an int array). The numbers differ from SPEC P3.4's numpy stream, so per-seed values
are not comparable with the reviewer's seeds 1-3, only the statistics.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import xarray as xr

from formation_ftc.blocks.controllers.networked_el_hinf import ELHinfConfig, adaptation_rate, control
from formation_ftc.blocks.fdi import FDIModel, fdi_output, fdi_params, isolation_routing
from formation_ftc.core import graph as graphs
from formation_ftc.core.disturbances import run_key, step_key
from formation_ftc.core.dynamics.euler_lagrange import (
    body_rates_from_euler_rates,
    euler_rates_from_body_rates,
    rigid_body_rhs,
)
from formation_ftc.core.expressions import compile_expression, compile_vector_expression
from formation_ftc.core.integrators import rk4_step
from formation_ftc.papers.mehrabian.schema import MehrabianScenario
from formation_ftc.registry import Compiled
from formation_ftc.sim.engine import run_fixed_step

__all__ = ["build", "WINDOWS", "AXES", "metrics_from_final", "neighbour_pairs"]

#: Metric windows, in this order in the accumulators.
WINDOWS = ("fault_window", "run", "assessment_window")
AXES = ("pitch", "roll", "yaw")
_MAX_FIELDS = ("sync_err_max", "track_err_max") + tuple(f"spread_max_{a}" for a in AXES) + tuple(
    f"abs_max_{a}" for a in AXES)


def neighbour_pairs(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each undirected link once (j < n), 0-based index arrays."""
    j, n = np.nonzero(np.triu(np.asarray(A) > 0, 1))
    return j, n



def build(s: MehrabianScenario) -> Compiled:
    """Compile a scenario (see the module docstring)."""
    m, nch = s.formation.n_spacecraft, 3
    dt, n_steps = s.simulation.dt, s.simulation.n_steps
    rec = s.simulation.record_every
    A = s.formation.adjacency()
    pj, pn = neighbour_pairs(A)
    idx = jnp.arange(1, m + 1, dtype=jnp.float64)
    desired = compile_vector_expression(s.desired.attitude, "desired.attitude")
    desired_d = jax.jacfwd(desired, argnums=0)
    desired_dd = jax.jacfwd(desired_d, argnums=0)
    cfg = ELHinfConfig(law=s.controller.law, compensation=s.controller.compensation)

    # faults: static structure (channel masks, expressions), windows in params
    masks = np.zeros((max(len(s.faults), 1), m, nch))
    fault_exprs = []
    for f_i, f in enumerate(s.faults):
        masks[f_i, f.spacecraft - 1, f.channel - 1] = 1.0
        fault_exprs.append((compile_expression(f.torque, ("t", "i"), field=f"faults[{f_i}].torque"), f.spacecraft))
    masks = masks[: len(s.faults)]
    fault_mask = masks.sum(axis=0) if len(s.faults) else np.zeros((m, nch))
    fdi_on = s.fdi.enabled and len(s.faults) > 0
    routing = isolation_routing(m, nch, {(e.spacecraft - 1, e.channel - 1): (e.reported_spacecraft - 1,
                                                                              e.reported_channel - 1)
                                         for e in s.fdi.isolation})
    onset = min((f.start for f in s.faults), default=0.0)

    c = s.controller
    ones = np.ones((m, nch))
    q0_fixed = np.deg2rad(np.asarray(s.initial.attitude_deg, dtype=float)) if s.initial.attitude_deg else np.zeros((m, nch))
    qdot0 = np.deg2rad(np.asarray(s.initial.rate_deg_s, dtype=float)) if s.initial.rate_deg_s else np.zeros((m, nch))
    windows = np.array([s.metrics.fault_window, (0.0, s.simulation.horizon), s.metrics.assessment_window])
    windows = np.minimum(windows, s.simulation.horizon)  # a shortened run clips its windows
    params = dict(
        seed=jnp.asarray(s.simulation.seed, dtype=jnp.uint32),
        random_initial=jnp.asarray(1.0 if s.initial.random else 0.0),
        q0_range=jnp.asarray(np.deg2rad(s.initial.attitude_range_deg)),
        q0_fixed=jnp.asarray(q0_fixed),
        qdot0=jnp.asarray(qdot0),
        J_nominal=jnp.asarray(np.tile(np.asarray(s.formation.nominal_inertia), (m, 1))),
        inertia_spread=jnp.asarray(s.formation.inertia_uncertainty),
        dist_std=jnp.asarray(np.sqrt(s.disturbance.variance)),
        K=jnp.asarray(c.K * ones), K_P=jnp.asarray(c.K_P * ones), K_I=jnp.asarray(c.K_I * ones),
        sigma=jnp.asarray(c.sigma * ones), e_gain=jnp.asarray(c.e_gain * ones),
        alpha=jnp.asarray(c.alpha * np.ones(m)), gamma=jnp.asarray(c.gamma * np.ones(m)),
        phi_b=jnp.asarray(c.boundary_layer),
        avg=jnp.asarray(graphs.row_normalized(A)),
        fault_window=jnp.asarray(np.array([(f.start, f.end) for f in s.faults]).reshape(-1, 2)),
        fdi=fdi_params(m, nch, fault_mask=fault_mask, onset=onset, delay=s.fdi.delay,
                       detected=s.fdi.detected, scale=s.fdi.scale, bias=s.fdi.bias,
                       noise_std=s.fdi.noise_std, routing=routing),
        windows=jnp.asarray(windows),
    )

    def make_fault_fn(p):
        kw = jnp.round(p["fault_window"] / dt).astype(jnp.int64)  # snapped [start, end] steps

        def fault_fn(k):
            out = jnp.zeros((m, nch))
            for f_i, (expr, sc) in enumerate(fault_exprs):
                on = (k >= kw[f_i, 0]) & (k <= kw[f_i, 1])
                out = out + masks[f_i] * jnp.where(on, expr(t=k * dt, i=float(sc)), 0.0)
            return out

        return fault_fn

    def setup(p):
        key = run_key(p["seed"])
        k_q0, k_J, k_d, k_fdi = jax.random.split(key, 4)
        lo, hi = p["q0_range"][0], p["q0_range"][1]
        q_rand = jax.random.uniform(k_q0, (m, nch), dtype=jnp.float64, minval=lo, maxval=hi)
        q0 = jnp.where(p["random_initial"] > 0.5, q_rand, p["q0_fixed"])
        delta = p["inertia_spread"] * jax.random.uniform(k_J, (m, nch), dtype=jnp.float64, minval=-1.0, maxval=1.0)
        J_true = jax.vmap(jnp.diag)(p["J_nominal"] * (1.0 + delta))
        J_hat = jax.vmap(jnp.diag)(p["J_nominal"])
        return dict(q0=q0, J=J_true, J_inv=jnp.linalg.inv(J_true), J_hat=J_hat, k_d=k_d, k_fdi=k_fdi)

    def flight_inputs(p, env, k):
        if fdi_on:
            model = FDIModel(m, nch, make_fault_fn(p), dt)
            out = fdi_output(model, p["fdi"], k, step_key(env["k_fdi"], k))
            return out.flag, out.estimate
        z = jnp.zeros((m, nch))
        return z, z

    def disturbance(p, env, k):
        """d_k ~ N(0, var I) per spacecraft/channel, held over step k (E003-11) [N m]."""
        return p["dist_std"] * jax.random.normal(step_key(env["k_d"], k), (m, nch), dtype=jnp.float64)

    def controller_at(t, x, flag, p, env):
        q, w = x["q"], x["w"]
        qdot = euler_rates_from_body_rates(q, w)
        e, ed, edd = desired(t, idx), desired_d(t, idx), desired_dd(t, idx)
        return qdot, control(q, qdot, x["z"], x["u_hat"], flag, e, ed, edd, env["J_hat"], p, cfg)

    def make_step(p):
        env = setup(p)
        fault_fn = make_fault_fn(p)
        kwin = jnp.round(p["windows"] / dt).astype(jnp.int64)

        def rhs(t, x, held):
            fault, d, flag, u_star, in_w = held
            _, ctl = controller_at(t, x, flag, p, env)
            q_dot, w_dot = rigid_body_rhs(x["q"], x["w"], ctl.u + fault + d, env["J"], env["J_inv"])
            qt = ctl.q_tilde
            sync2 = jnp.mean(jnp.sum((qt[pj] - qt[pn]) ** 2, axis=-1))
            track2 = jnp.mean(jnp.sum(qt**2, axis=-1))
            effort = jnp.sum(ctl.u**2)
            return dict(q=q_dot, w=w_dot, z=qt,
                        u_hat=adaptation_rate(ctl.s, x["u_hat"], u_star, flag, p["sigma"], p["e_gain"]),
                        integrals=in_w[:, None] * jnp.stack([sync2, track2, effort])[None, :],
                        maxima=jnp.zeros_like(x["maxima"]))

        def step(k, x):
            t = k * dt
            fault = fault_fn(k)  # truth: actuator chain, held over the step
            d = disturbance(p, env, k)
            flag, u_star = flight_inputs(p, env, k)
            in_w = ((k >= kwin[:, 0]) & (k < kwin[:, 1])).astype(jnp.float64)
            e = desired(t, idx)
            qt = x["q"] - e
            now = jnp.concatenate([
                jnp.stack([jnp.max(jnp.linalg.norm(qt[pj] - qt[pn], axis=-1)),
                           jnp.max(jnp.linalg.norm(qt, axis=-1))]),
                jnp.max(x["q"], axis=0) - jnp.min(x["q"], axis=0),
                jnp.max(jnp.abs(x["q"]), axis=0),
            ])
            maxima = jnp.where(in_w[:, None] > 0, jnp.maximum(x["maxima"], now[None, :]), x["maxima"])
            new = rk4_step(rhs, t, x, dt, (fault, d, flag, u_star, in_w))
            new["maxima"] = maxima
            return new

        return step

    def initial_state(p):
        env = setup(p)
        q0 = env["q0"]
        return dict(q=q0, w=body_rates_from_euler_rates(q0, p["qdot0"]), z=jnp.zeros((m, nch)),
                    u_hat=jnp.zeros((m, nch)), integrals=jnp.zeros((len(WINDOWS), 3)),
                    maxima=jnp.zeros((len(WINDOWS), len(_MAX_FIELDS))))

    def observe(k, x, p):
        env = setup(p)
        t = k * dt
        flag, u_star = flight_inputs(p, env, k)
        qdot, ctl = controller_at(t, x, flag, p, env)
        return dict(q=x["q"], qdot=qdot, u=ctl.u, s=ctl.s, u_hat=x["u_hat"], flag=flag, u_star=u_star,
                    fault=make_fault_fn(p)(k), disturbance=disturbance(p, env, k))

    def run(p):
        return run_fixed_step(make_step(p), lambda k, x: observe(k, x, p), initial_state(p),
                              n_steps, rec, s.simulation.unroll)

    def to_dataset(out, n_rec):
        r = out["records"]
        time = np.arange(n_rec) * dt * rec
        dims = ("time", "spacecraft", "axis")
        return xr.Dataset(
            {
                "attitude": (dims, r["q"], {"units": "rad", "long_name": "Euler angles [theta, phi, psi]"}),
                "attitude_rate": (dims, r["qdot"], {"units": "rad/s"}),
                "control": (dims, r["u"], {"units": "N m", "long_name": "commanded generalised force u (6)"}),
                "sliding_variable": (dims, r["s"], {"units": "rad/s"}),
                "fault_estimate_adaptive": (dims, r["u_hat"], {"units": "N m", "long_name": "u^ of (19)"}),
                "fdi_flag": (dims, r["flag"], {"units": "1"}),
                "fdi_estimate": (dims, r["u_star"], {"units": "N m", "long_name": "u* reported by the FDI"}),
                "fault": (dims, r["fault"], {"units": "N m", "long_name": "true additive fault u_bar (2)"}),
                "disturbance": (dims, r["disturbance"], {"units": "N m", "long_name": "input disturbance d, "
                                                                                     "held over the step"}),
            },
            coords={"time": ("time", time, {"units": "s"}), "spacecraft": np.arange(1, m + 1), "axis": list(AXES)},
        )

    def metrics(out):
        return metrics_from_final(out["final"], windows, m)

    key = ("mehrabian", m, tuple(map(tuple, A.astype(int).tolist())), tuple(s.desired.attitude),
           tuple((f.spacecraft, f.channel, f.torque) for f in s.faults), fdi_on, cfg,
           n_steps, rec, dt, s.simulation.unroll)
    return Compiled(run=run, params=params, static_key=key, dt=dt, record_every=rec, to_dataset=to_dataset,
                    metrics=metrics, make_step=make_step,
                    spacecraft_axis=lambda name: None if name in ("integrals", "maxima") else 0)


def metrics_from_final(final, windows, m: int) -> dict[str, np.ndarray]:
    """Scalar metrics from the final accumulators; works on a batch (leading axes) as well.

    sync_err_rms = sqrt(1/T int mean_pairs |q~_j - q~_n|^2 dt) [rad]; track_err_rms = sqrt(1/T int
    mean_j |q~_j|^2 dt) [rad]; control_effort = int sum_j |u_j|^2 dt [(N m)^2 s]; control_rms =
    sqrt(effort / (m T)) [N m]; maxima over the window's steps [rad].
    """
    I = np.asarray(final["integrals"])
    M = np.asarray(final["maxima"])
    windows = np.asarray(windows)
    out: dict[str, np.ndarray] = {}
    for w_i, name in enumerate(WINDOWS):
        T = float(windows[w_i, 1] - windows[w_i, 0])
        if T <= 0:  # window after the horizon (shortened run): no metrics
            continue
        out[f"sync_err_rms_{name}"] = np.sqrt(I[..., w_i, 0] / T)
        out[f"track_err_rms_{name}"] = np.sqrt(I[..., w_i, 1] / T)
        out[f"control_effort_{name}"] = I[..., w_i, 2]
        out[f"control_rms_{name}"] = np.sqrt(I[..., w_i, 2] / (m * T))
        for f_i, field in enumerate(_MAX_FIELDS):
            out[f"{field}_{name}"] = M[..., w_i, f_i]
    if np.ndim(out["sync_err_rms_run"]) == 0:
        return {k: float(v) for k, v in out.items()}
    return out
