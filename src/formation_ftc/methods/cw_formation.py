"""``cw-formation``: N deputies on linear Clohessy-Wiltshire dynamics with composable parts.

The worked example of the method contract (:mod:`formation_ftc.registry`) and a small playground that
combines the shared building blocks: CW plant (:mod:`formation_ftc.core.dynamics.cw`), a PD formation
controller, actuator faults written as expressions (loss of effectiveness, additive bias), external
disturbance forces, process and sensor noise (seeded), RK4 integration with the controller either
evaluated at every RK stage (``controller.mode = "continuous"``) or held over the step
(``"sampled"``, zero-order hold).

Model per deputy i (mass m_i [kg], x radial, y along-track, z orbit normal)::

    q_dot = A q + B (Gamma_i(t) u_i + delta_i(t) + d_i(t) + w_i) / m_i
    u_i   = -kp (p_i - p_i^d(t)) - kd (v_i - v_i^d(t)) + m^nom_i a_i^d(t)  (PD + feed-forward, measured state)

``m^nom_i`` is ``controller.nominal_mass`` (default :data:`NOMINAL_MASS` = 100 kg), the law's stated
knowledge: the true masses ``spacecraft.mass`` drive the plant only.

``p^d(t)`` is an expression; ``v^d`` and ``a^d`` are its exact time derivatives (JAX autodiff).
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from pydantic import Field, model_validator

from formation_ftc.components.actuators.expression_faults import ExpressionFaultActuator
from formation_ftc.components.controllers.pd_formation import PdFormationController, ZeroController
from formation_ftc.components.plants.clohessy_wiltshire import ClohessyWiltshirePlant
from formation_ftc.components.sensors.relative_state import RelativeStateSensors
from formation_ftc.config.base import ExprText, ScenarioBase, StrictModel
from formation_ftc.config.sections import SpacecraftSection
from formation_ftc.core.orbit import MU_EARTH
from formation_ftc.registry import Condition, Method, register_method
from formation_ftc.sim.compiled import Compiled, compile_loop
from formation_ftc.sim.components import as_float
from formation_ftc.sim.loop import ClosedLoop
from formation_ftc.sim.metrics import Metric

__all__ = ["CwFormationScenario", "build", "make_loop"]

Vec3Expr = tuple[ExprText, ExprText, ExprText]

#: the PD law's nominal on-board mass when a scenario states none [kg] (``controller.nominal_mass``)
NOMINAL_MASS = 100.0


class OrbitSection(StrictModel):
    mean_motion: float | None = Field(
        None, gt=0, description="Mean motion n of the circular reference [rad/s]."
    )
    semi_major_axis: float | None = Field(
        None, gt=0, description="Radius of the circular reference [m] (if n not given)."
    )
    mu: float = Field(MU_EARTH, gt=0, description="Gravitational parameter [m^3/s^2].")

    @model_validator(mode="after")
    def _one_of(self):
        if (self.mean_motion is None) == (self.semi_major_axis is None):
            raise ValueError(
                "orbit: give exactly one of orbit.mean_motion [rad/s] or orbit.semi_major_axis [m]"
            )
        return self

    @property
    def n(self) -> float:
        if self.mean_motion is not None:
            return self.mean_motion
        assert self.semi_major_axis is not None  # the validator requires exactly one of the two
        return float(np.sqrt(self.mu / self.semi_major_axis**3))


class ControllerSection(StrictModel):
    type: Literal["none", "pd"] = Field(
        "none", description="'none' (free drift) or 'pd' formation keeping."
    )
    mode: Literal["continuous", "sampled"] = Field(
        "continuous", description="Controller at every RK stage or held over the step."
    )
    kp: float = Field(0.0, ge=0, description="Position gain [N/m].")
    kd: float = Field(0.0, ge=0, description="Velocity gain [N s/m].")
    desired_position: Vec3Expr = Field(
        ("0", "0", "0"),
        description="Desired LVLH position p^d(t) per axis, expressions in t [s], i [m].",
    )
    max_force: float | None = Field(
        None, gt=0, description="Per-axis saturation of the commanded force [N]."
    )
    nominal_mass: float | list[float] = Field(
        NOMINAL_MASS,
        description=(
            "Masses the PD law knows on board, used by its feed-forward m_i a_i^d [kg], > 0: one number for every "
            "deputy or one per deputy. Default 100 kg, a stated nominal value: never the true spacecraft.mass, so "
            "a campaign that samples the true mass leaves the law's knowledge unchanged."
        ),
    )

    @model_validator(mode="after")
    def _positive_masses(self):
        values = self.nominal_mass if isinstance(self.nominal_mass, list) else [self.nominal_mass]
        if not values or any(not (math.isfinite(m) and m > 0) for m in values):
            raise ValueError(
                f"controller.nominal_mass = {self.nominal_mass}: every mass must be finite and > 0 kg"
            )
        return self


class FaultSection(StrictModel):
    effectiveness: Vec3Expr = Field(
        ("1", "1", "1"),
        description="Multiplicative effectiveness Gamma(t) per axis [-], in (0, 1].",
    )
    bias: Vec3Expr = Field(
        ("0", "0", "0"), description="Additive actuator fault delta(t) per axis [N]."
    )


class DisturbanceSection(StrictModel):
    force: Vec3Expr = Field(
        ("0", "0", "0"), description="External disturbance force d(t) per axis [N]."
    )
    process_noise_std: float = Field(
        0.0, ge=0, description="Std of a per-step Gaussian force (ZOH) [N]."
    )


class SensorSection(StrictModel):
    position_noise_std: float = Field(
        0.0, ge=0, description="Std of position measurement noise [m]."
    )
    velocity_noise_std: float = Field(
        0.0, ge=0, description="Std of velocity measurement noise [m/s]."
    )


class CwFormationScenario(ScenarioBase):
    orbit: OrbitSection
    spacecraft: SpacecraftSection
    controller: ControllerSection = ControllerSection()
    faults: FaultSection = FaultSection()
    disturbance: DisturbanceSection = DisturbanceSection()
    sensors: SensorSection = SensorSection()

    @model_validator(mode="after")
    def _nominal_masses_per_deputy(self):
        m = self.controller.nominal_mass
        if isinstance(m, list) and len(m) != self.spacecraft.count:
            raise ValueError(
                f"controller.nominal_mass: {len(m)} values for {self.spacecraft.count} spacecraft "
                f"(give one number or {self.spacecraft.count})"
            )
        return self


def make_loop(s: CwFormationScenario) -> ClosedLoop:
    """The scenario as a composition of components (every number a leaf, every choice static)."""
    N = s.spacecraft.count
    v0 = (
        np.zeros((N, 3))
        if s.spacecraft.initial_velocity is None
        else np.asarray(s.spacecraft.initial_velocity)
    )
    mass = as_float(s.spacecraft.mass)
    plant = ClohessyWiltshirePlant(
        mean_motion=as_float(s.orbit.n),
        mass=mass,
        initial_state_lvlh=as_float(np.hstack([np.asarray(s.spacecraft.initial_position), v0])),
        process_noise_std=as_float(s.disturbance.process_noise_std),
        disturbance_force=s.disturbance.force,
    )
    if s.controller.type == "pd":
        sat = s.controller.max_force
        controller: PdFormationController | ZeroController = PdFormationController(
            count=N,
            kp=as_float(s.controller.kp),
            kd=as_float(s.controller.kd),
            mass=as_float(
                np.broadcast_to(np.asarray(s.controller.nominal_mass, float), (N,)).copy()
            ),
            max_force=as_float(np.inf if sat is None else sat),
            desired_position=s.controller.desired_position,
            is_sampled=s.controller.mode == "sampled",
        )
    else:
        controller = ZeroController(count=N)
    sensors = RelativeStateSensors(
        count=N,
        position_noise_std=as_float(s.sensors.position_noise_std),
        velocity_noise_std=as_float(s.sensors.velocity_noise_std),
    )
    actuator = ExpressionFaultActuator(
        count=N, effectiveness=s.faults.effectiveness, bias=s.faults.bias
    )
    metrics = []
    if s.controller.type == "pd":
        metrics += [
            Metric(
                "max_position_error",
                "position_error",
                reduce="max",
                norm=True,
                spacecraft="max",
                units="m",
            ),
            Metric(
                "final_position_error_mean",
                "position_error",
                reduce="final",
                norm=True,
                spacecraft="mean",
                units="m",
            ),
        ]
    metrics += [
        Metric("delta_v", "delta_v", reduce="final", spacecraft="each", units="m s-1"),
        Metric("control_effort", "control_effort", reduce="final", spacecraft="each", units="N2 s"),
        Metric("delta_v_total", "delta_v", reduce="final", spacecraft="sum", units="m s-1"),
    ]
    sim = s.simulation
    return ClosedLoop.from_simulation(
        sim,
        plant=plant,
        controller=controller,
        sensors=sensors,
        actuator=actuator,
        metrics=tuple(metrics),
    )


def build(s: CwFormationScenario) -> Compiled:
    """Compile a CW formation scenario (see module docstring)."""
    return compile_loop(make_loop(s))


def rk4_amplification(z: np.ndarray) -> np.ndarray:
    """|R(z)| of classical RK4, R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24 (z = lambda dt): a mode is
    integrated stably when |R(z)| <= 1."""
    z = np.asarray(z, dtype=complex)
    return np.abs(1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24)


def check(s: CwFormationScenario) -> list[Condition]:
    """PD on CW: closed-loop eigenvalues of A - B [kp kd]/m must have negative real parts, and the
    RK4 step must integrate every closed-loop mode stably (|R(lambda dt)| <= 1, computed exactly from
    the eigenvalues). Both are exact for the linear model up to the eigenvalues' rounding margin
    (:func:`formation_ftc.core.rounding.eigenvalue_margin`): a real part within the margin of 0 does
    not count as stable."""
    out = []
    n = s.orbit.n
    from formation_ftc.core.dynamics.cw import cw_matrices
    from formation_ftc.core.rounding import eigenvalue_margin

    A, B = cw_matrices(n)
    if s.controller.type != "pd":
        eigs = [np.linalg.eigvals(A)]
        margins = [np.full(A.shape[0], eigenvalue_margin(A))]
    else:
        eigs, margins = [], []
        for i, m in enumerate(s.spacecraft.mass):
            K = np.hstack([s.controller.kp * np.eye(3), s.controller.kd * np.eye(3)]) / m
            M = A - B @ K
            ev = np.linalg.eigvals(M)
            tol = eigenvalue_margin(M)
            eigs.append(ev)
            margins.append(np.full(ev.shape, tol))
            out.append(
                Condition(
                    name=f"closed-loop stable, spacecraft {i + 1}",
                    reference="linear CW + PD",
                    value=f"max Re(eig) = {ev.real.max():.4g} 1/s",
                    requirement=f"< -{tol:.2g} (rounding margin)",
                    holds=bool(ev.real.max() < -tol),
                    required=True,
                    basis="exact",
                    detail=f"exact: eigenvalues of the 6 x 6 closed-loop matrix (LAPACK, float64), rounding margin "
                    f"{tol:.2g} 1/s (Bauer-Fike: kappa(V) 10 n eps ||A - BK||)",
                )
            )
    ev_all = np.concatenate(eigs)
    tol_all = np.concatenate(margins)
    dt = s.simulation.dt
    amp = rk4_amplification(ev_all * dt)
    worst = int(np.argmax(amp))
    stable_modes = ev_all.real < -tol_all
    # a mode that is stable in continuous time must stay damped by the RK4 step (|R| <= 1)
    ok = bool(np.all(amp[stable_modes] <= 1.0)) if stable_modes.any() else True
    out.append(
        Condition(
            name="RK4 step vs closed-loop modes",
            reference="RK4 stability region",
            value=f"dt max|lambda| = {dt * np.abs(ev_all).max():.3g}, max |R(lambda dt)| = {amp.max():.4g} "
            f"(at lambda = {ev_all[worst]:.3g} 1/s)",
            requirement="|R(lambda dt)| <= 1 for every stable mode",
            holds=ok,
            required=True,
            basis="exact",
            detail="exact for the linear closed loop: RK4 amplification factor R(z) = 1 + z + z^2/2 + z^3/6 + "
            "z^4/24 evaluated at every closed-loop eigenvalue times dt (LAPACK eigenvalues; modes within "
            "the rounding margin of the imaginary axis are not counted as stable)",
        )
    )
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


register_method(
    Method(
        name="cw-formation",
        schema=CwFormationScenario,
        build=build,
        description="N deputies on linear CW dynamics, PD control, faults, noise",
        check=check,
        plot=plot,
    )
)
