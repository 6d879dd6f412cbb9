"""``cw-formation``: N deputies on linear Clohessy-Wiltshire dynamics with composable parts.

The worked example of the method contract (:mod:`formation_ftc.registry`) and a small playground that
combines the shared building blocks: CW plant (:mod:`formation_ftc.core.dynamics.cw`), a PD formation
controller, actuator faults written as expressions (loss of effectiveness, additive bias), external
disturbance forces, process and sensor noise (seeded), RK4 integration with the controller either
evaluated at every RK stage (``controller.mode = "continuous"``) or held over the step
(``"sampled"``, zero-order hold).

Model per deputy i (mass m_i [kg], x radial, y along-track, z orbit normal; SPEC.md 0.3)::

    q_dot = A q + B (Gamma_i(t) u_i + delta_i(t) + d_i(t) + w_i) / m_i
    u_i   = -kp (p_i - p_i^d(t)) - kd (v_i - v_i^d(t)) + m_i a_i^d(t)  (PD + feed-forward, measured state)

``p^d(t)`` is an expression; ``v^d`` and ``a^d`` are its exact time derivatives (JAX autodiff).
"""

from __future__ import annotations

from typing import Literal

import jax
import jax.numpy as jnp
import numpy as np
import xarray as xr
from pydantic import Field, model_validator

from formation_ftc.config.base import ExprText, ScenarioBase, StrictModel
from formation_ftc.config.sections import SpacecraftSection
from formation_ftc.core.disturbances import gaussian_noise, run_key, step_key
from formation_ftc.core.dynamics.cw import cw_rhs
from formation_ftc.core.expressions import compile_vector_expression
from formation_ftc.core.faults import actuator_fault
from formation_ftc.core.integrators import rk4_step
from formation_ftc.core.orbit import MU_EARTH
from formation_ftc.registry import Compiled, Condition, Method, register_method
from formation_ftc.sim.engine import run_fixed_step

__all__ = ["CwFormationScenario", "build"]

Vec3Expr = tuple[ExprText, ExprText, ExprText]


class OrbitSection(StrictModel):
    mean_motion: float | None = Field(None, gt=0, description="Mean motion n of the circular reference [rad/s].")
    semi_major_axis: float | None = Field(None, gt=0, description="Radius of the circular reference [m] (if n not given).")
    mu: float = Field(MU_EARTH, gt=0, description="Gravitational parameter [m^3/s^2].")

    @model_validator(mode="after")
    def _one_of(self):
        if (self.mean_motion is None) == (self.semi_major_axis is None):
            raise ValueError("orbit: give exactly one of orbit.mean_motion [rad/s] or orbit.semi_major_axis [m]")
        return self

    @property
    def n(self) -> float:
        return self.mean_motion if self.mean_motion is not None else float(np.sqrt(self.mu / self.semi_major_axis**3))


class ControllerSection(StrictModel):
    type: Literal["none", "pd"] = Field("none", description="'none' (free drift) or 'pd' formation keeping.")
    mode: Literal["continuous", "sampled"] = Field("continuous", description="Controller at every RK stage or held over the step.")
    kp: float = Field(0.0, ge=0, description="Position gain [N/m].")
    kd: float = Field(0.0, ge=0, description="Velocity gain [N s/m].")
    desired_position: Vec3Expr = Field(("0", "0", "0"), description="Desired LVLH position p^d(t) per axis, expressions in t [s], i [m].")
    max_force: float | None = Field(None, gt=0, description="Per-axis saturation of the commanded force [N].")


class FaultSection(StrictModel):
    effectiveness: Vec3Expr = Field(("1", "1", "1"), description="Multiplicative effectiveness Gamma(t) per axis [-], in (0, 1].")
    bias: Vec3Expr = Field(("0", "0", "0"), description="Additive actuator fault delta(t) per axis [N].")


class DisturbanceSection(StrictModel):
    force: Vec3Expr = Field(("0", "0", "0"), description="External disturbance force d(t) per axis [N].")
    process_noise_std: float = Field(0.0, ge=0, description="Std of a per-step Gaussian force (ZOH) [N].")


class SensorSection(StrictModel):
    position_noise_std: float = Field(0.0, ge=0, description="Std of position measurement noise [m].")
    velocity_noise_std: float = Field(0.0, ge=0, description="Std of velocity measurement noise [m/s].")


class CwFormationScenario(ScenarioBase):
    orbit: OrbitSection
    spacecraft: SpacecraftSection
    controller: ControllerSection = ControllerSection()
    faults: FaultSection = FaultSection()
    disturbance: DisturbanceSection = DisturbanceSection()
    sensors: SensorSection = SensorSection()



def build(s: CwFormationScenario) -> Compiled:
    """Compile a CW formation scenario (see module docstring)."""
    N = s.spacecraft.count
    dt = s.simulation.dt
    idx = jnp.arange(1, N + 1, dtype=jnp.float64)  # 1-based spacecraft number for expressions
    desired = compile_vector_expression(s.controller.desired_position, "controller.desired_position")
    gamma = compile_vector_expression(s.faults.effectiveness, "faults.effectiveness")
    bias = compile_vector_expression(s.faults.bias, "faults.bias")
    dist = compile_vector_expression(s.disturbance.force, "disturbance.force")
    d_vel = jax.jacfwd(desired, argnums=0)
    d_acc = jax.jacfwd(d_vel, argnums=0)
    pd = s.controller.type == "pd"
    continuous = s.controller.mode == "continuous"
    sat = s.controller.max_force

    v0 = np.zeros((N, 3)) if s.spacecraft.initial_velocity is None else np.asarray(s.spacecraft.initial_velocity)
    params = dict(
        n=jnp.asarray(s.orbit.n), mass=jnp.asarray(s.spacecraft.mass), kp=jnp.asarray(s.controller.kp),
        kd=jnp.asarray(s.controller.kd), q0=jnp.asarray(np.hstack([np.asarray(s.spacecraft.initial_position), v0])),
        process_std=jnp.asarray(s.disturbance.process_noise_std),
        pos_std=jnp.asarray(s.sensors.position_noise_std), vel_std=jnp.asarray(s.sensors.velocity_noise_std),
        seed=jnp.asarray(s.simulation.seed, dtype=jnp.uint32),
    )

    def control(t, q_meas, p):
        if not pd:
            return jnp.zeros((N, 3))
        pdes, vdes, ades = desired(t, idx), d_vel(t, idx), d_acc(t, idx)
        u = -p["kp"] * (q_meas[:, :3] - pdes) - p["kd"] * (q_meas[:, 3:] - vdes) + p["mass"][:, None] * ades
        return jnp.clip(u, -sat, sat) if sat is not None else u

    def make_step(p):
        key = run_key(p["seed"])

        def rhs(t, x, u_held, w, noise):
            q = x["q"]
            u = control(t, q + noise, p) if continuous else u_held
            f = actuator_fault(u, gamma(t, idx), bias(t, idx)) + dist(t, idx) + w
            return {"q": cw_rhs(t, q, f / p["mass"][:, None], p["n"]),
                    "dv": jnp.linalg.norm(u, axis=-1) / p["mass"], "effort": jnp.sum(u**2, axis=-1)}

        def step(k, x):
            t = k * dt
            kk = step_key(key, k)
            k1, k2, k3 = jax.random.split(kk, 3)
            w = gaussian_noise(k1, (N, 3), p["process_std"])
            noise = jnp.concatenate([gaussian_noise(k2, (N, 3), p["pos_std"]),
                                     gaussian_noise(k3, (N, 3), p["vel_std"])], axis=-1)
            u_held = control(t, x["q"] + noise, p)  # used only in sampled-data mode
            return rk4_step(rhs, t, x, dt, u_held, w, noise)

        return step

    def observe(k, x, p):
        t = k * dt
        u = control(t, x["q"], p)
        err = x["q"][:, :3] - desired(t, idx) if pd else jnp.zeros((N, 3))
        return {"q": x["q"], "u": u, "pos_err": err}

    def run(p):
        x0 = {"q": p["q0"], "dv": jnp.zeros(N), "effort": jnp.zeros(N)}
        return run_fixed_step(make_step(p), lambda k, x: observe(k, x, p), x0,
                              s.simulation.n_steps, s.simulation.record_every, s.simulation.unroll)

    def to_dataset(out, n_rec):
        r = out["records"]
        time = np.arange(n_rec) * dt * s.simulation.record_every
        sc = np.arange(1, N + 1)
        ax = ["x", "y", "z"]
        q = r["q"]
        return xr.Dataset(
            {
                "position": (("time", "spacecraft", "axis"), q[..., :3], {"units": "m", "frame": "LVLH"}),
                "velocity": (("time", "spacecraft", "axis"), q[..., 3:], {"units": "m/s", "frame": "LVLH"}),
                "control": (("time", "spacecraft", "axis"), r["u"], {"units": "N"}),
                "position_error": (("time", "spacecraft", "axis"), r["pos_err"], {"units": "m"}),
            },
            coords={"time": ("time", time, {"units": "s"}), "spacecraft": sc, "axis": ax},
        )

    def metrics(out):
        r, fin = out["records"], out["final"]
        e = np.linalg.norm(r["pos_err"], axis=-1)
        m = {"max_position_error": float(e.max()), "final_position_error_mean": float(e[-1].mean())}
        for i in range(N):
            m[f"delta_v_sc{i + 1}"] = float(fin["dv"][i])
            m[f"control_effort_sc{i + 1}"] = float(fin["effort"][i])
        m["delta_v_total"] = float(np.sum(fin["dv"]))
        return m

    key = ("cw-formation", N, tuple(s.controller.desired_position), tuple(s.faults.effectiveness),
           tuple(s.faults.bias), tuple(s.disturbance.force), pd, continuous, sat,
           s.simulation.n_steps, s.simulation.record_every, dt, s.simulation.unroll)
    return Compiled(run=run, params=params, static_key=key, dt=dt, record_every=s.simulation.record_every,
                    to_dataset=to_dataset, metrics=metrics, make_step=make_step,
                    spacecraft_axis=lambda name: 0)


def check(s: CwFormationScenario) -> list[Condition]:
    """PD on CW: closed-loop eigenvalues of A - B [kp kd]/m must have negative real parts."""
    out = []
    n = s.orbit.n
    from formation_ftc.core.dynamics.cw import cw_matrices

    A, B = cw_matrices(n)
    for i, m in enumerate(s.spacecraft.mass):
        if s.controller.type != "pd":
            break
        K = np.hstack([s.controller.kp * np.eye(3), s.controller.kd * np.eye(3)]) / m
        ev = np.linalg.eigvals(A - B @ K)
        out.append(Condition(
            name=f"closed-loop stable, spacecraft {i + 1}", reference="linear CW + PD",
            value=f"max Re(eig) = {ev.real.max():.4g} 1/s", requirement="< 0",
            holds=bool(ev.real.max() < 0), required=True))
    step_ok = s.simulation.dt * max(s.controller.kp, 1e-300) / min(s.spacecraft.mass) < 2.0
    out.append(Condition(name="RK4 step vs stiffness", reference="dt * kp / m",
                         value=f"{s.simulation.dt * s.controller.kp / min(s.spacecraft.mass):.3g}",
                         requirement="< 2 (well inside RK4 stability)", holds=bool(step_ok), required=False))
    return out


def plot(ds, scenario, out_dir):
    from formation_ftc.plotting import new_figure, save_figure

    fig, axes = new_figure(3, 1, title=f"{scenario.scenario.name}: LVLH position")
    for k, ax_name in enumerate(["x", "y", "z"]):
        ax = axes[k, 0]
        for sc in ds.spacecraft.values:
            ax.plot(ds.time, ds.position.sel(spacecraft=sc, axis=ax_name), label=f"spacecraft {sc}")
        ax.set_ylabel(f"{ax_name} [m]")
    axes[-1, 0].set_xlabel("time [s]")
    axes[0, 0].legend(loc="best")
    return [save_figure(fig, out_dir / "position.png")]


register_method(Method(name="cw-formation", schema=CwFormationScenario, build=build,
                       description="N deputies on linear CW dynamics, PD control, faults, noise",
                       check=check, plot=plot))
