"""Method ``li2020``: the closed loops of Li et al. 2020 (Thm 1, Thm 2 with delays, SIR-FTC baseline).

Plant: :mod:`formation_ftc.core.dynamics.relative_lvlh` (eqs. (1)-(4)); faults eq. (5)
``F_i = Gamma_i(t) f_i + delta_i(t)``; disturbance h_i(t); desired formation
:mod:`.desired`; controllers :mod:`formation_ftc.blocks.controllers.li2020_adaptive` and
:mod:`formation_ftc.blocks.controllers.sir_ftc`.

One step k -> k+1 (t_k = k dt):

1. RK4 over [t_k, t_k + dt]; at every stage the controller is evaluated (continuous-time law) and the
   adaptive states are integrated with the plant. The reference true anomaly theta (autonomous, the
   same for every spacecraft and every run of a batch) is stepped first and its four stage values
   (r_c, theta_dot, theta_ddot) are handed to the spacecraft stages
   (:func:`formation_ftc.core.integrators.rk4_autonomous_stages`; same numbers as joint RK4). Everything that depends on time only (desired
   trajectory, sigma, faults, disturbances, delays) is evaluated once per step, batched over the three
   distinct stage times t_k, t_k + dt/2, t_k + dt (fewer XLA kernels per step). Fault/disturbance
   expressions use the left limit t_{k+1}^- at the last stage so that a fault onset on the step grid
   never falls inside an RK step.
2. Thm 2: at a stage time t agent i reads s_j(t - T_ij(t)) from the history ring buffer
   (:mod:`formation_ftc.core.history`, linear interpolation, constant prehistory s_j(0), SPEC 0.2);
   the newest stored sample is s(t_k).
3. After the step: s(t_{k+1}) is pushed into the history.

State: ``{"x": {theta, rho, v, adaptive states, dv, effort}, "hist": History}``. ``dv`` integrates
||f_i|| / m_i (commanded delta-v [m/s]) and ``effort`` integrates ||f_i||^2 [N^2 s].
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import xarray as xr

from formation_ftc.blocks.controllers.li2020_adaptive import (
    consensus_term,
    li2020_adaptation_rates,
    li2020_control,
    sigma_exponential,
    sigma_inverse_square,
)
from formation_ftc.blocks.controllers.sir_ftc import sir_epsilon, sir_ftc_control, sir_ftc_rate
from formation_ftc.core.dynamics.relative_lvlh import natural_acceleration_from_rates, reference_rates
from formation_ftc.core.expressions import compile_vector_expression
from formation_ftc.core.history import history_init, history_push, history_read, required_capacity
from formation_ftc.core.integrators import rk4_autonomous_stages, rk4_step_staged
from formation_ftc.core.vector3 import norm3, sq_norm3
from formation_ftc.papers.li2020.conditions import delay_statistics, delay_vector_function
from formation_ftc.papers.li2020.desired import chi_from_period, desired_trajectory, formation_offsets
from formation_ftc.papers.li2020.metrics import (
    max_over_window,
    mu1,
    mu2_literal,
    mu2_virtual_centre,
    settle_time,
)
from formation_ftc.papers.li2020.schema import Li2020Scenario
from formation_ftc.registry import Compiled
from formation_ftc.sim.engine import run_fixed_step

__all__ = ["build", "make_params", "make_model", "LEFT_LIMIT"]

#: fraction of dt subtracted from the last RK stage time for fault/disturbance expressions
LEFT_LIMIT = 1e-9



def make_params(s: Li2020Scenario) -> dict:
    """Numeric parameter pytree (everything a Monte Carlo campaign may vary)."""
    N = s.spacecraft.count
    o = s.orbit
    fm = s.formation
    chi = fm.chi if fm.chi is not None else chi_from_period(o.period, fm.completion_fraction, fm.completion_residual)
    v0 = np.zeros((N, 3)) if s.spacecraft.initial_velocity is None else np.asarray(s.spacecraft.initial_velocity)
    literal_sign = s.controller.dhat_sign_literal and s.controller.law == "thm2"
    sir = s.sir_ftc
    p = dict(
        mass=np.asarray(s.spacecraft.mass, float), p=o.semi_latus_rectum, e=o.eccentricity, mu=o.mu,
        theta0=o.true_anomaly0, rho0=np.asarray(s.spacecraft.initial_position, float), v0=v0,
        C=np.asarray(s.network.adjacency, float),
        rho_bar=formation_offsets(fm.radius, fm.phase), chi=chi, rotation=fm.rotation, growth=fm.growth,
        centre=np.asarray(fm.centre_offset, float),
        k=s.per_spacecraft("k"), lam=s.per_spacecraft("lam"), gamma=s.per_spacecraft("gamma"),
        eta=s.per_spacecraft("eta"), mu_a=s.per_spacecraft("mu"), upsilon=s.per_spacecraft("upsilon"),
        m_hat0=s.per_spacecraft("m_hat0"), beta_hat0=s.per_spacecraft("beta_hat0"),
        d_hat0=s.per_spacecraft("d_hat0"), sigma_a=s.per_spacecraft("sigma_a"), sigma_t0=s.controller.sigma_t0,
        d_sign=-1.0 if literal_sign else 1.0,
        k0=sir.k0, phi=sir.phi, sigma1=sir.sigma1, sigma2=sir.sigma2, mu_s=sir.mu_s,
        b_hat0=np.full(N, sir.b_hat0),
    )
    if s.faults.profile == "step":
        dt = float(s.simulation.dt)
        p["fault_alpha"] = np.asarray(s.faults.step_effectiveness, float)
        # onsets snapped to the step grid so that no RK step straddles a fault onset
        p["fault_onset"] = np.round(np.asarray(s.faults.step_onset, float) / dt) * dt
    return jax.tree_util.tree_map(lambda a: jnp.asarray(a, dtype=jnp.float64), p)


def make_model(s: Li2020Scenario):
    """Pure pieces of the closed loop: ``(init_state, make_step, observe, static)``.

    ``init_state(p)``, ``make_step(p) -> step(k, state)``, ``observe(p, k, state) -> dict``.
    """
    N = s.spacecraft.count
    dt = float(s.simulation.dt)
    law = s.controller.law
    delayed = law == "thm2"
    adaptive = law in ("thm1", "thm2")
    idx = jnp.arange(1, N + 1, dtype=jnp.float64)
    if s.faults.profile == "step":
        def gamma_fn(t, _idx, p):  # Li2020 eq. (5) with a step loss of effectiveness per channel
            return jnp.where(t >= p["fault_onset"], p["fault_alpha"], 1.0)
    else:
        _gamma_expr = compile_vector_expression(s.faults.effectiveness_texts(), "faults.effectiveness")

        def gamma_fn(t, i, _p):
            return _gamma_expr(t, i)
    delta_fn = compile_vector_expression(s.faults.additive, "faults.additive")
    h_fn = compile_vector_expression(s.disturbance.force, "disturbance.force")
    exp_sigma = s.controller.sigma_form == "exponential"
    C_np = np.asarray(s.network.adjacency, float)
    if delayed:
        pairs = [(int(i), int(j)) for i, j in zip(*np.nonzero(C_np > 0), strict=True)]
        T_fn = delay_vector_function([[str(x) for x in r] for r in s.network.delays], pairs)
        edge_rows = np.array([i for i, _ in pairs], dtype=int)
        edge_cols = np.array([j for _, j in pairs], dtype=int)
        sender_onehot = np.eye(N)[edge_cols]  # (E, N)
        receiver_onehot = np.eye(N)[edge_rows].T  # (N, E)
        used = {(st.pair): st for st in delay_statistics(s)}
        t_max = max((used[pr].value_max for pr in pairs), default=0.0)
        capacity = required_capacity(t_max, dt) + 1
    else:
        T_fn, capacity = None, 0

    def sigma_of(t, p):
        return sigma_exponential(t, p["sigma_a"]) if exp_sigma else sigma_inverse_square(t, p["sigma_a"], p["sigma_t0"])

    def time_values(t, t_fault, p):
        """Everything that depends on time only (desired trajectory, sigma, faults, disturbance, delays)."""
        rho_d, v_d, a_d, rho_f = desired_trajectory(t, p["rho_bar"], p["chi"], p["rotation"], p["growth"],
                                                    p["centre"])
        tv = dict(rho_d=rho_d, v_d=v_d, a_d=a_d, rho_f=rho_f, sigma=sigma_of(t, p),
                  Gam=gamma_fn(t_fault, idx, p), delta=delta_fn(t_fault, idx), h=h_fn(t_fault, idx))
        if delayed:
            tv["T"] = T_fn(t)
        return tv

    def stage_table(t_k, p):
        """time_values at the three distinct RK4 stage times t_k, t_k + dt/2, t_k + dt (one batched
        evaluation per step; faults at the left limit t_{k+1}^- for the last stage)."""
        ts = t_k + dt * jnp.array([0.0, 0.5, 1.0])
        tf = t_k + dt * jnp.array([0.0, 0.5, 1.0 - LEFT_LIMIT])
        return jax.vmap(lambda a, b: time_values(a, b, p))(ts, tf)

    def sliding(x, tv, p):
        e1 = x["rho"] - tv["rho_d"]  # eq. (6)
        e2 = x["v"] - tv["v_d"]
        return e2 + p["k"][:, None] * e1, e1, e2

    def delayed_consensus(s_, t, t_k, T, hist, p):
        """sum_j c_ij (s_i(t) - s_j(t - T_ij(t))) over the used edges (eq. (42)); history newest = s(t_k)."""
        lag = (T - (t - t_k)) / dt  # (E,) steps before the newest sample (>= 0 since T >= dt)
        rows_all = history_read(hist, lag)  # (E, N, 3): every sender's s at each edge's delayed time
        # dense selections instead of gathers/scatters (much faster on XLA:CPU)
        s_j = jnp.einsum("en,enk->ek", sender_onehot, rows_all)  # (E, 3): s_{j_e}(t - T_e)
        c_e = jnp.sum(p["C"][edge_rows] * sender_onehot, axis=1)  # (E,) edge weights c_{i_e j_e}
        in_weight = jnp.sum(p["C"], axis=1)
        recv = receiver_onehot @ (c_e[:, None] * s_j)  # (N, 3)
        return in_weight[:, None] * s_ - recv

    def evaluate(t, x, tv, orb, t_k, hist, p):
        """Derivatives of x (theta excepted) and outputs; ``orb = (r_c, theta_dot, theta_ddot)``."""
        s_, e1, e2 = sliding(x, tv, p)
        acc_nat = natural_acceleration_from_rates(x["rho"], x["v"], *orb, p["mu"])
        Y = acc_nat + p["k"][:, None] * (x["v"] - tv["v_d"]) - tv["a_d"]  # eq. (8)
        sig = tv["sigma"]
        deriv = {}
        if adaptive:
            if delayed:
                cons = delayed_consensus(s_, t, t_k, tv["T"], hist, p)  # eq. (42)
            else:
                cons = consensus_term(p["C"], s_)  # eq. (24)
            f, xi = li2020_control(s_, Y, cons, x["m_hat"], x["beta_hat"], x["d_hat"], sig, p["lam"],
                                   p["d_sign"])
            deriv["beta_hat"], deriv["m_hat"], deriv["d_hat"] = li2020_adaptation_rates(
                s_, Y, xi, x["d_hat"], sig, p["gamma"], p["eta"], p["mu_a"], p["upsilon"])
        else:
            eps = sir_epsilon(p["mu_s"], p["phi"])
            f = sir_ftc_control(s_, x["b_hat"], p["k0"], p["phi"], eps)
            deriv["b_hat"] = sir_ftc_rate(s_, x["b_hat"], p["phi"], eps, p["sigma1"], p["sigma2"])
        F = tv["Gam"] * f + tv["delta"]  # eq. (5)
        deriv.update(rho=x["v"], v=acc_nat + (tv["h"] + F) / p["mass"][:, None],  # eq. (1)
                     dv=norm3(f) / p["mass"], effort=sq_norm3(f))
        extra = dict(e1=e1, e2=e2, s=s_, f=f, F=F)
        return deriv, extra

    def init_state(p):
        x = {"theta": p["theta0"], "rho": p["rho0"], "v": p["v0"], "dv": jnp.zeros(N), "effort": jnp.zeros(N)}
        if adaptive:
            x.update(m_hat=p["m_hat0"], beta_hat=p["beta_hat0"], d_hat=p["d_hat0"])
        else:
            x["b_hat"] = p["b_hat0"]
        state = {"x": x}
        if delayed:
            s0 = sliding(x, time_values(0.0, 0.0, p), p)[0]
            state["hist"] = history_init(s0, capacity)
        return state

    def make_step(p):
        def rhs(t, x, stage, t_k, hist):
            tv, orb = stage
            return evaluate(t, x, tv, orb, t_k, hist, p)[0]

        def theta_dot(theta):
            return reference_rates(theta, p["p"], p["e"], p["mu"])[1]

        def step(k, state):
            t_k = k * dt
            hist = state.get("hist")
            table = stage_table(t_k, p)
            tvs = [jax.tree_util.tree_map(lambda a, j=j: a[j], table) for j in (0, 1, 1, 2)]
            # the reference orbit (Li2020 eq. (1)'s theta) is autonomous and independent of the spacecraft:
            # its RK4 stage values are computed first, once per step (not per run of a batch)
            theta, theta_stages = rk4_autonomous_stages(theta_dot, state["x"]["theta"], dt)
            # the rates are evaluated again, as one (4,) vector: a vector with four consumers is
            # materialised once by XLA, whereas the scalar rates of each stage would be fused into that
            # stage's (runs, N, 3) kernel and their cos/sin evaluated per element (4 scalar cos/sin per
            # step spent to save 4 x runs x N x 3)
            orbit = reference_rates(jnp.stack(theta_stages), p["p"], p["e"], p["mu"])  # each (4,)
            stages = tuple((tvs[j], tuple(o[j] for o in orbit)) for j in range(4))
            xs = {name: v for name, v in state["x"].items() if name != "theta"}
            x = dict(rk4_step_staged(rhs, t_k, xs, dt, stages, t_k, hist), theta=theta)
            new = {"x": x}
            if delayed:
                tv_next = jax.tree_util.tree_map(lambda a: a[2], table)  # t_{k+1} (desired part is exact)
                new["hist"] = history_push(hist, sliding(x, tv_next, p)[0])
            return new

        return step

    def observe(p, k, state):
        t = k * dt
        x = state["x"]
        tv = time_values(t, t, p)
        orb = reference_rates(x["theta"], p["p"], p["e"], p["mu"])
        _, extra = evaluate(t, x, tv, orb, t, state.get("hist"), p)
        rec = dict(rho=x["rho"], v=x["v"], e1=extra["e1"], e2=extra["e2"], f=extra["f"], F=extra["F"],
                   effectiveness=tv["Gam"], dv=x["dv"], effort=x["effort"], theta=x["theta"],
                   mu1=mu1(extra["e1"]), mu2=mu2_literal(x["rho"]),
                   mu2_vc=mu2_virtual_centre(x["rho"], tv["rho_f"]))
        for name in ("m_hat", "beta_hat", "d_hat", "b_hat"):
            if name in x:
                rec[name] = x[name]
        return rec

    static = dict(N=N, dt=dt, law=law, delayed=delayed, capacity=capacity, adaptive=adaptive)
    return init_state, make_step, observe, static


def build(s: Li2020Scenario) -> Compiled:
    """Compile a ``li2020`` scenario (see module docstring)."""
    init_state, make_step, observe, static = make_model(s)
    N, dt = static["N"], static["dt"]
    sim = s.simulation
    n_steps, rec_every = sim.n_steps, sim.record_every

    def run(p):
        # the history only holds copies of s(t_k) computed from x: checking x suffices
        return run_fixed_step(make_step(p), lambda k, st: observe(p, k, st), init_state(p), n_steps,
                              rec_every, sim.unroll, check_of=lambda st: st["x"])

    def to_dataset(out, n_rec):
        r = out["records"]
        time = np.arange(n_rec) * dt * rec_every
        vec = ("time", "spacecraft", "axis")
        per = ("time", "spacecraft")
        data = {
            "position": (vec, r["rho"], {"units": "m", "frame": "LVLH", "long_name": "rho_i"}),
            "velocity": (vec, r["v"], {"units": "m/s", "frame": "LVLH", "long_name": "v_i"}),
            "position_error": (vec, r["e1"], {"units": "m", "long_name": "e_i1"}),
            "velocity_error": (vec, r["e2"], {"units": "m/s", "long_name": "e_i2"}),
            "control": (vec, r["f"], {"units": "N", "long_name": "commanded f_i"}),
            "applied_force": (vec, r["F"], {"units": "N", "long_name": "F_i = Gamma_i f_i + delta_i"}),
            "effectiveness": (vec, r["effectiveness"], {"units": "1", "long_name": "alpha_ij"}),
            "delta_v": (per, r["dv"], {"units": "m/s", "long_name": "int ||f_i||/m_i dt"}),
            "control_effort": (per, r["effort"], {"units": "N^2 s", "long_name": "int ||f_i||^2 dt"}),
            "true_anomaly": (("time",), r["theta"], {"units": "rad"}),
            "mu1": (("time",), r["mu1"], {"units": "m", "long_name": "formation tracking error"}),
            "mu2": (("time",), r["mu2"], {"units": "m", "long_name": "formation keeping error (literal, E000-08)"}),
            "mu2_vc": (("time",), r["mu2_vc"], {"units": "m", "long_name": "virtual-centre formation keeping error"}),
        }
        units = {"m_hat": "kg", "beta_hat": "1", "d_hat": "N", "b_hat": "N"}
        for name, u in units.items():
            if name in r:
                data[name] = (per, r[name], {"units": u})
        return xr.Dataset(data, coords={"time": ("time", time, {"units": "s"}),
                                        "spacecraft": np.arange(1, N + 1), "axis": ["x", "y", "z"]})

    def metrics(out):
        r, fin = out["records"], out["final"]["x"]
        n_rec = len(r["mu1"])
        time = np.arange(n_rec) * dt * rec_every
        m1 = np.asarray(r["mu1"])
        t_end = time[-1]
        res = {
            "mu1_final": float(m1[-1]),
            "mu2_final": float(np.asarray(r["mu2"])[-1]),
            "mu2_vc_final": float(np.asarray(r["mu2_vc"])[-1]),
            "mu1_max_last_10pct": max_over_window(time, m1, 0.9 * t_end),
            "settle_time_mu1_1m": settle_time(time, m1, 1.0),
            "mu1_max_after_50s": max_over_window(time, m1, 50.0),
            "delta_v_total": float(np.sum(fin["dv"])),
            "max_control_force": float(np.max(np.abs(np.asarray(r["f"])))),
        }
        for tq in (10.0, 20.0, 30.0, 100.0, 300.0, 1000.0, 3000.0):
            kq = int(round(tq / (dt * rec_every)))
            if kq < n_rec:
                res[f"mu1_at_{int(tq)}s"] = float(m1[kq])
        e1n = np.linalg.norm(np.asarray(r["e1"])[-1], axis=-1)
        e2n = np.linalg.norm(np.asarray(r["e2"])[-1], axis=-1)
        for i in range(N):
            res[f"delta_v_sc{i + 1}"] = float(fin["dv"][i])
            res[f"position_error_final_sc{i + 1}"] = float(e1n[i])
            res[f"velocity_error_final_sc{i + 1}"] = float(e2n[i])
            for name in ("m_hat", "beta_hat", "d_hat", "b_hat"):
                if name in fin:
                    res[f"{name}_final_sc{i + 1}"] = float(fin[name][i])
        return res

    key = ("li2020", N, s.controller.law, s.controller.sigma_form, s.faults.profile,
           s.faults.effectiveness_texts() if s.faults.profile == "expressions" else None,
           tuple(s.faults.additive), tuple(s.disturbance.force),
           None if s.network.delays is None or not static["delayed"] else tuple(map(tuple, s.network.delays)),
           tuple(map(tuple, (np.asarray(s.network.adjacency) > 0).tolist())) if static["delayed"] else None,
           static["capacity"], n_steps, rec_every, dt, sim.unroll)

    def spacecraft_axis(name: str):
        if name.startswith("hist"):
            return 1 if name.endswith("values") else None
        return None if name.endswith("theta") else 0

    return Compiled(run=run, params=make_params(s), static_key=key, dt=dt, record_every=rec_every,
                    to_dataset=to_dataset, metrics=metrics, make_step=make_step,
                    spacecraft_axis=spacecraft_axis)
