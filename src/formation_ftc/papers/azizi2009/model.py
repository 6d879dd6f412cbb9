"""The ``azizi2009`` closed loop: deep-space formation of N double integrators, relative-output
formation control on a chain, LLFR allocation, HL supervisor and FLFR (Azizi & Khorasani 2009;
SPEC.md P4.2-P4.4).

One control step k (t_k = k dt; ARCHITECTURE.md "One control step"):

1. measure the relative errors e_ij = x_j - x_i - x_ij^d and their rates on the chain pairs, plus
   seeded Gaussian noise (E004-09, default off);
2. HL supervisor (:mod:`formation_ftc.blocks.supervisors.hierarchical_supervisor`): Nominal -> LLFR
   when the fault estimate arrives, LLFR -> FLFR when the measured max |e_ij| exceeds e_s;
3. controller p_ij = xdd_ij^d - lambda1 e'_ij - lambda0 e_ij (Sec. II) and allocation
   u = J_aug^-1 [p; 0] (eq. (3)) with the mode's (alpha, b_hat) -- one precomputed allocation matrix per
   mode and axis, selected by the integer mode (branch-free);
4. truth side: applied acceleration b_i u_i + d_i with the true (faulty) gains; exact ZOH update of the
   double integrators (``sampling = 'zoh'``) or RK4 with the control re-evaluated at the stages
   (``'continuous'``);
5. accumulate the cumulative effort E_i = int u_i^2 dt and the running max of the true |e_ij|.

Desired formation (SPEC P4.2): regular N-gon (a square of side 200 m for N = 4) rotating
counter-clockwise at omega in the xy plane, satellite i at angle omega t + pi/4 + (i-1) 2 pi / N.
"""

from __future__ import annotations

import functools
import json

import jax
import jax.numpy as jnp
import numpy as np
import xarray as xr

from formation_ftc.blocks.supervisors.hierarchical_supervisor import (
    FLFR,
    MODE_NAMES,
    HierarchicalSupervisor,
    SupervisorState,
    events,
)
from formation_ftc.core.disturbances import gaussian_noise, step_key
from formation_ftc.core.dynamics.double_integrator import DoubleIntegratorState, rhs, zoh_step
from formation_ftc.core.expressions import compile_expression
from formation_ftc.core.integrators import rk4_step
from formation_ftc.design.allocation import allocation_matrix, augmented_matrix, validate_allocation_inputs
from formation_ftc.design.flfr import FlfrDesign, design_flfr
from formation_ftc.papers.azizi2009.schema import Azizi2009Scenario
from formation_ftc.registry import Compiled
from formation_ftc.sim.engine import run_fixed_step

__all__ = ["desired_state", "relative_acceleration_fn", "flfr_design", "build", "AXES"]

AXES = ("x", "y", "z")


def desired_state(t, n: int, n_axes: int, side, omega):
    """Desired positions [m], velocities [m/s], accelerations [m/s^2], each (N, n_axes) (SPEC P4.2)."""
    i = jnp.arange(n)
    radius = side / (2.0 * jnp.sin(jnp.pi / n))
    phase = omega * t + jnp.pi / 4 + i * (2.0 * jnp.pi / n)
    c, s = jnp.cos(phase), jnp.sin(phase)
    pos = jnp.stack([radius * c, radius * s, jnp.zeros_like(c)], axis=-1)[:, :n_axes]
    vel = jnp.stack([-radius * omega * s, radius * omega * c, jnp.zeros_like(c)], axis=-1)[:, :n_axes]
    acc = jnp.stack([-radius * omega**2 * c, -radius * omega**2 * s, jnp.zeros_like(c)], axis=-1)[:, :n_axes]
    return pos, vel, acc


def _rel(x):
    """Chain differences x_{i+1} - x_i along the satellite axis (-2)."""
    return x[..., 1:, :] - x[..., :-1, :]


@functools.lru_cache(maxsize=64)
def relative_acceleration_fn(n: int, side: float, omega: float, axis: int):
    """t -> desired relative accelerations xdd_{i,i+1}^d(t) on one axis, shape (N-1,) [m/s^2].

    Cached so that the same function object (a static jit argument of the H_i simulation) is reused.
    """

    def fn(t):
        _, _, acc = desired_state(t, n, 3, side, omega)
        return acc[1:, axis] - acc[:-1, axis]

    return fn


def _b_hat_estimated(sc: Azizi2009Scenario) -> np.ndarray:
    na = sc.formation.n_axes
    b_nom = np.tile(np.asarray(sc.formation.b, float)[:, None], (1, na))
    b_hat = b_nom.copy()
    if sc.fault.enabled:
        b_hat[sc.fault.satellite - 1, "xyz".index(sc.fault.axis)] = sc.fault.estimate
    return b_hat


def _b_true(sc: Azizi2009Scenario) -> np.ndarray:
    na = sc.formation.n_axes
    b_nom = np.tile(np.asarray(sc.formation.b, float)[:, None], (1, na))
    b = b_nom.copy()
    if sc.fault.enabled:
        k, a = sc.fault.satellite - 1, "xyz".index(sc.fault.axis)
        b[k, a] = b_nom[k, a] * sc.fault.effectiveness
    return b


@functools.lru_cache(maxsize=32)
def _design_cached(key: tuple) -> FlfrDesign:
    (alpha, b_hat, k, b_eps, lam0, lam1, e_s, pis, n, side, omega, axis, horizon, dt, b_ext, a_ref) = key
    w_fn = relative_acceleration_fn(n, side, omega, axis)
    return design_flfr(np.asarray(alpha), np.asarray(b_hat), k, b_eps, lam0, lam1, e_s, pis, w_fn,
                       horizon, dt, b_ext, a_ref)


def flfr_design(sc: Azizi2009Scenario, pis=None, e_s: float | None = None) -> FlfrDesign:
    """Offline FLFR design (eqs. (8)-(11)) for the scenario's faulty satellite/axis (cached by inputs).

    H_i is simulated over 300 s (the sup over t needs several rotation periods and the transient).
    """
    if not sc.fault.enabled:
        raise ValueError("FLFR design needs fault.enabled = true")
    axis = "xyz".index(sc.fault.axis)
    pis = tuple(float(p) for p in (pis if pis is not None else (sc.supervisor.violation_probability,)))
    key = (tuple(float(a) for a in sc.allocation.alpha), tuple(float(b) for b in _b_hat_estimated(sc)[:, axis]),
           sc.fault.satellite - 1, float(sc.fault.b_eps), float(sc.controller.lambda0),
           float(sc.controller.lambda1), float(e_s if e_s is not None else sc.supervisor.e_s), pis,
           sc.formation.n_satellites, float(sc.formation.side), float(sc.formation.omega), axis,
           300.0, float(sc.supervisor.design_dt), float(sc.disturbance.bound),
           float(sc.supervisor.alpha_reference))
    return _design_cached(key)


def _alpha_flfr(sc: Azizi2009Scenario) -> float:
    k = sc.fault.satellite - 1
    if sc.supervisor.alpha_flfr is not None:
        return float(sc.supervisor.alpha_flfr)
    if not (sc.supervisor.flfr and sc.fault.enabled):
        return float(sc.allocation.alpha[k])
    des = flfr_design(sc)
    if des.verdict == "infeasible":
        raise ValueError(f"supervisor: {des.message}")
    a = des.alpha[float(sc.supervisor.violation_probability)]
    return max(float(a), float(sc.allocation.alpha[k]))  # never lower the weight (LLFR already suffices)


def build(sc: Azizi2009Scenario) -> Compiled:
    """Compile a scenario (see module docstring).

    ``params["alpha_flfr"]`` is designed offline (eq. (11)) from the scenario's own weights; a batch that
    varies ``alpha`` in a supervised (``supervisor.flfr``) scenario should vary ``alpha_flfr`` with it.
    """
    fm, sim = sc.formation, sc.simulation
    n, na = fm.n_satellites, fm.n_axes
    dt = sim.dt
    n_steps = sim.n_steps
    k_fault = sc.fault.satellite - 1
    ax_fault = "xyz".index(sc.fault.axis)
    b_nom = np.tile(np.asarray(fm.b, float)[:, None], (1, na))
    b_hat_est = _b_hat_estimated(sc)
    for a in range(na):
        validate_allocation_inputs(sc.allocation.alpha, b_hat_est[:, a])
    never = n_steps + 1
    k_onset = round(sc.fault.onset / dt) if sc.fault.enabled else never
    k_est = round(sc.fault.estimated_at / dt) if sc.fault.enabled else never
    alpha_flfr = _alpha_flfr(sc)
    noise_on = sc.noise.sigma_position > 0 or sc.noise.sigma_velocity > 0
    continuous = sc.controller.sampling == "continuous"
    dist = compile_expression(sc.disturbance.acceleration, ("t", "i"))
    sup = HierarchicalSupervisor()
    offset = np.zeros(n) if fm.initial_offset_x is None else np.asarray(fm.initial_offset_x, float)

    params = {
        "lambda0": jnp.asarray(sc.controller.lambda0), "lambda1": jnp.asarray(sc.controller.lambda1),
        "alpha": jnp.asarray(sc.allocation.alpha, dtype=jnp.float64), "alpha_flfr": jnp.asarray(alpha_flfr),
        "b_nominal": jnp.asarray(b_nom), "b_faulty": jnp.asarray(_b_true(sc)), "b_hat": jnp.asarray(b_hat_est),
        "k_onset": jnp.asarray(k_onset, jnp.int64), "k_estimated": jnp.asarray(k_est, jnp.int64),
        "e_s": jnp.asarray(sc.supervisor.e_s),
        "flfr_enabled": jnp.asarray(bool(sc.supervisor.flfr and sc.fault.enabled)),
        "confirm_steps": jnp.asarray(round(sc.supervisor.confirm_time / dt), jnp.int64),
        "monitor_start": jnp.asarray(round(sc.supervisor.monitor_start / dt), jnp.int64),
        "settle_steps": jnp.asarray(round(sc.supervisor.settle_time / dt), jnp.int64),
        "sigma_position": jnp.asarray(sc.noise.sigma_position),
        "sigma_velocity": jnp.asarray(sc.noise.sigma_velocity),
        "side": jnp.asarray(fm.side), "omega": jnp.asarray(fm.omega),
        "initial_offset_x": jnp.asarray(offset), "seed": jnp.asarray(sim.seed, jnp.int64),
    }
    ones_axes = jnp.ones((na,))

    def setup(p):
        # mode-dependent allocation matrices (n_modes, n_axes, N, N-1): Nominal uses the nominal gains
        alpha_f = p["alpha"].at[k_fault].set(p["alpha_flfr"])
        alphas = jnp.stack([p["alpha"], p["alpha"], alpha_f])
        b_hats = jnp.stack([p["b_nominal"], p["b_hat"], p["b_hat"]])  # (3, N, axes)
        Ms = jax.vmap(lambda a, bh: jax.vmap(lambda bcol: allocation_matrix(a, bcol), in_axes=1)(bh))(alphas, b_hats)
        # ||D|| of eq. (6) with the true eps on the faulty axis, for the LLFR and FLFR weights
        eps = p["b_hat"][k_fault, ax_fault] - p["b_faulty"][k_fault, ax_fault]
        E = jnp.zeros((n - 1, n))
        if 0 < k_fault:
            E = E.at[k_fault - 1, k_fault].set(-eps)
        if k_fault < n - 1:
            E = E.at[k_fault, k_fault].set(eps)

        def dnorm(a):
            return jnp.linalg.norm(E @ jnp.linalg.inv(augmented_matrix(a, p["b_hat"][:, ax_fault])), 2)

        return Ms, jnp.stack([dnorm(p["alpha"]), dnorm(alpha_f)])

    def make_step(p):
        Ms, _ = setup(p)
        key = jax.random.PRNGKey(p["seed"])
        lam0, lam1 = p["lambda0"], p["lambda1"]
        i1 = jnp.arange(1, n + 1, dtype=jnp.float64)

        def disturbance(t):
            return jnp.broadcast_to(dist(t=t, i=i1), (n,))[:, None] * ones_axes

        def control(t, r, v, M, noise_r, noise_v):
            rd, vd, ad = desired_state(t, n, na, p["side"], p["omega"])
            e = _rel(r) - _rel(rd) + noise_r
            ed = _rel(v) - _rel(vd) + noise_v
            pc = _rel(ad) - lam1 * ed - lam0 * e  # Azizi2009 Sec. II, p_ij
            return jnp.einsum("anm,ma->na", M, pc)  # eq. (3)

        def step(k, s):
            t = k * dt
            if noise_on:
                kr, kv = jax.random.split(step_key(key, k))
                nr = gaussian_noise(kr, (n - 1, na), p["sigma_position"])
                nv = gaussian_noise(kv, (n - 1, na), p["sigma_velocity"])
            else:
                nr = nv = jnp.zeros((n - 1, na))
            # (1) measure, (2) supervisor on the measured error
            rd, vd, ad = desired_state(t, n, na, p["side"], p["omega"])
            e_true = _rel(s["r"]) - _rel(rd)
            e_meas = e_true + nr
            sup_state = sup.step(s["sup"], k, jnp.max(jnp.abs(e_meas)), k_estimated=p["k_estimated"],
                                 e_s=p["e_s"], confirm_steps=p["confirm_steps"],
                                 monitor_start=p["monitor_start"], flfr_enabled=p["flfr_enabled"])
            M = Ms[sup_state.mode]
            b = jnp.where(k >= p["k_onset"], p["b_faulty"], p["b_nominal"])  # truth side
            x = DoubleIntegratorState(s["r"], s["v"])
            # (3) controller and allocation at t_k
            pc = _rel(ad) - lam1 * (_rel(s["v"]) - _rel(vd) + nv) - lam0 * e_meas  # Sec. II, p_ij
            u = jnp.einsum("anm,ma->na", M, pc)  # eq. (3)
            # (4) truth-side plant over the step
            if continuous:
                def f(tt, xx):
                    uu = control(tt, xx.r, xx.v, M, nr, nv)
                    return rhs(tt, xx, uu, b, disturbance(tt))
                x_new = rk4_step(f, t, x, dt)
            else:
                x_new = zoh_step(x, u, b, disturbance(t), dt)
            # (5) metrics on the true error at t_k (the final state is covered by the records)
            err = jnp.abs(e_true)
            in_flfr = jnp.where(sup_state.mode == FLFR, s["flfr_steps"] + 1, 0)
            settled = in_flfr > p["settle_steps"]
            return {
                "r": x_new.r, "v": x_new.v, "u": u, "effort": s["effort"] + u * u * dt,
                "max_err": jnp.maximum(s["max_err"], err),
                "max_err_flfr": jnp.where(settled, jnp.maximum(s["max_err_flfr"], jnp.max(err)), s["max_err_flfr"]),
                "flfr_steps": in_flfr, "sup": sup_state, "D_norm": s["D_norm"],
            }

        return step

    def initial_state(p):
        _, dn = setup(p)
        rd, vd, _ = desired_state(0.0, n, na, p["side"], p["omega"])
        r0 = rd.at[:, 0].add(p["initial_offset_x"])
        return {"r": r0, "v": vd, "u": jnp.zeros((n, na)), "effort": jnp.zeros((n, na)),
                "max_err": jnp.zeros((n - 1, na)), "max_err_flfr": jnp.asarray(-1.0),
                "flfr_steps": jnp.asarray(0, jnp.int64), "sup": sup.init(), "D_norm": dn}

    def run(p):
        step = make_step(p)

        def obs(k, s):
            rd, _, _ = desired_state(k * dt, n, na, p["side"], p["omega"])
            return {"r": s["r"], "v": s["v"], "u": s["u"], "effort": s["effort"], "mode": s["sup"].mode,
                    "error": _rel(s["r"]) - _rel(rd)}

        return run_fixed_step(step, obs, initial_state(p), n_steps, sim.record_every, sim.unroll)

    def to_dataset(out: dict, n_records: int) -> xr.Dataset:
        rec = {key: np.asarray(v)[:n_records] for key, v in out["records"].items()}
        t = np.arange(n_records) * dt * sim.record_every
        final = out["final"]
        sup_final = SupervisorState(*[np.asarray(x) for x in final["sup"]])
        ev = events(sup_final, dt)
        pairs = [f"{j + 1}-{j + 2}" for j in range(n - 1)]
        coords = {"time": ("time", t, {"units": "s"}), "spacecraft": np.arange(1, n + 1),
                  "axis": list(AXES[:na]), "pair": pairs}
        rd = np.asarray(jax.vmap(lambda tt: desired_state(tt, n, na, fm.side, fm.omega)[0])(jnp.asarray(t)))
        ds = xr.Dataset(
            {
                "position": (("time", "spacecraft", "axis"), rec["r"], {"units": "m"}),
                "velocity": (("time", "spacecraft", "axis"), rec["v"], {"units": "m/s"}),
                "desired_position": (("time", "spacecraft", "axis"), rd, {"units": "m"}),
                "control": (("time", "spacecraft", "axis"), rec["u"],
                            {"units": "N per unit gain", "long_name": "allocated input u_i (held over the step)"}),
                "effort": (("time", "spacecraft", "axis"), rec["effort"],
                           {"units": "N^2 s", "long_name": "cumulative effort E_i = int u_i^2 dt"}),
                "tracking_error": (("time", "pair", "axis"), rec["error"], {"units": "m"}),
                "mode": (("time",), rec["mode"], {"long_name": "HL supervisor mode: " + ", ".join(
                    f"{j} = {m}" for j, m in enumerate(MODE_NAMES))}),
                "max_abs_error": (("pair", "axis"), np.asarray(final["max_err"]), {"units": "m"}),
            },
            coords=coords,
        )
        ds.attrs.update({
            "events": json.dumps(ev), "alpha_flfr": float(np.asarray(params["alpha_flfr"])),
            "D_norm_llfr": float(np.asarray(final["D_norm"])[0]),
            "D_norm_flfr": float(np.asarray(final["D_norm"])[1]),
        })
        return ds

    def metrics(out: dict) -> dict[str, float]:
        final = out["final"]
        me = np.asarray(final["max_err"])
        res = {"max_err": float(me.max()), "max_err_x": float(me[:, 0].max()),
               "max_err_after_flfr": float(np.asarray(final["max_err_flfr"])),
               "D_norm_llfr": float(np.asarray(final["D_norm"])[0]),
               "D_norm_flfr": float(np.asarray(final["D_norm"])[1])}
        if res["max_err_after_flfr"] < 0:
            res["max_err_after_flfr"] = float("nan")
        sup_final = SupervisorState(*[np.asarray(x) for x in final["sup"]])
        ev = events(sup_final, dt)
        t_flfr = [e["time"] for e in ev if e["to"] == "FLFR"]
        res["t_flfr"] = float(t_flfr[0]) if t_flfr else float("nan")
        res["n_events"] = float(len(ev))
        eff = np.asarray(final["effort"])
        for j in range(n):
            res[f"effort_x_{j + 1}"] = float(eff[j, 0])
        k100 = round(100.0 / (dt * sim.record_every))
        recs = np.asarray(out["records"]["effort"])
        if abs(k100 * dt * sim.record_every - 100.0) < 1e-9 and k100 < recs.shape[0]:
            for j in range(n):
                res[f"effort_x_100s_{j + 1}"] = float(recs[k100, j, 0])
        return res

    def spacecraft_axis(name: str) -> int | None:
        return 0 if name in ("r", "v", "u", "effort") else None

    static_key = ("azizi2009", n, na, n_steps, sim.record_every, sim.unroll, dt, k_fault, ax_fault,
                  noise_on, continuous, sc.disturbance.acceleration)
    return Compiled(run=run, params=params, static_key=static_key, dt=dt, record_every=sim.record_every,
                    to_dataset=to_dataset, metrics=metrics, make_step=make_step, spacecraft_axis=spacecraft_axis)
