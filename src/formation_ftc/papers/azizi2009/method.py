"""Method ``azizi2009``: the deep-space formation of Azizi & Khorasani 2009 (N double integrators,
relative-output formation control on a chain, LLFR allocation, HL supervisor and FLFR) as a
composition of components.

* plant :class:`~formation_ftc.components.plants.double_integrator.DoubleIntegratorPlant`
  (``x_i'' = b_i u_i + d_i``; exact zero-order-hold step for ``controller.sampling = 'zoh'``, RK4 with
  the control re-evaluated at the stages for ``'continuous'``) with the disturbance d_i(t) (E004-10);
* sensors :class:`~formation_ftc.components.sensors.chain_relative.ChainRelativeSensors`: relative
  positions and velocities on the chain pairs with seeded Gaussian noise (E004-09, default off);
* supervisor :class:`~formation_ftc.components.supervisors.hierarchical.HierarchicalSupervisor`:
  Nominal -> LLFR when the fault estimate arrives, LLFR -> FLFR when the measured max |e_ij| exceeds
  e_s;
* controller :class:`~formation_ftc.components.controllers.azizi2009_llfr.ChainLlfrController`:
  p_ij = xdd_ij^d - lambda1 e'_ij - lambda0 e_ij (Sec. II) and u = J_aug^-1 [p; 0] (eq. (3)) with the
  mode's (alpha, b_hat) -- one allocation matrix per mode and axis, computed once per run;
* actuator :class:`~formation_ftc.components.actuators.actuator_gains.StepGainActuator`: the true
  (faulty) gains b_i(t) on the truth side;
* evaluations: the true chain errors ``tracking_error`` and the flag ``flfr_settled`` (FLFR active for
  longer than ``supervisor.settle_time``) that opens the window of ``max_err_after_flfr``.

Desired formation: regular N-gon (a square of side 200 m for N = 4) rotating counter-clockwise at
omega in the xy plane, satellite i at angle omega t + pi/4 + (i-1) 2 pi / N
(:func:`formation_ftc.core.polygon_formation.rotating_polygon`). Metrics are accumulated at every step
inside the run; ``effort`` integrates u_i^2 of the command per spacecraft and axis.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any, cast

import jax
import jax.numpy as jnp
import numpy as np

from formation_ftc.blocks.supervisors.hierarchical_supervisor import FLFR
from formation_ftc.components.actuators.actuator_gains import StepGainActuator
from formation_ftc.components.controllers.azizi2009_llfr import ChainLlfrController
from formation_ftc.components.evaluations.chain_errors import ChainTrackingError, ThresholdFlag
from formation_ftc.components.plants.double_integrator import DoubleIntegratorPlant
from formation_ftc.components.sensors.chain_relative import ChainRelativeSensors
from formation_ftc.components.supervisors.hierarchical import HierarchicalSupervisor
from formation_ftc.config import loader
from formation_ftc.core.polygon_formation import rotating_polygon
from formation_ftc.design.allocation import validate_allocation_inputs
from formation_ftc.papers.azizi2009.conditions import (
    alpha_flfr,
    b_hat_estimated,
    b_nominal,
    b_true,
    check,
    d_norms,
)
from formation_ftc.papers.azizi2009.schema import Azizi2009Scenario
from formation_ftc.registry import Method, register_method
from formation_ftc.sim.batch import batched_grid_run, batched_run, stack_params, stack_params_grid
from formation_ftc.sim.compiled import Compiled, compile_loop
from formation_ftc.sim.components import as_float
from formation_ftc.sim.loop import ClosedLoop
from formation_ftc.sim.metrics import Metric, metrics_dict

__all__ = [
    "make_loop",
    "build",
    "load",
    "simulate",
    "run_batch",
    "plot",
    "METHOD",
    "EFFORT_TIME",
    "VARIABLE",
]

#: time of the ``effort_x_100s_sc*`` metrics (Fig. 2 compares the efforts there) [s]
EFFORT_TIME = 100.0

#: the desired formation evaluated by XLA (the same numbers the run computes in its loop)
_desired_state = jax.jit(rotating_polygon, static_argnums=(1, 2))


# --------------------------------------------------------------------------------------------------
# the composition
# --------------------------------------------------------------------------------------------------
def make_loop(sc: Azizi2009Scenario) -> ClosedLoop:
    """The scenario as a composition of components (see module docstring).

    The FLFR weight ``controller.alpha_flfr`` is designed offline (eq. (11)) from the scenario's own
    weights; a batch that varies ``controller.alpha`` in a supervised scenario should vary it with it.
    """
    fm, sim = sc.formation, sc.simulation
    n, na, dt = fm.n_satellites, fm.n_axes, sim.dt
    b_nom = b_nominal(sc)
    b_hat = b_hat_estimated(sc)
    for a in range(na):
        validate_allocation_inputs(sc.allocation.alpha, b_hat[:, a])
    never = sim.n_steps + 1
    k_onset = round(sc.fault.onset / dt) if sc.fault.enabled else never
    k_est = round(sc.fault.estimated_at / dt) if sc.fault.enabled else never
    continuous = sc.controller.sampling == "continuous"
    offset = np.zeros(n) if fm.initial_offset_x is None else np.asarray(fm.initial_offset_x, float)
    side, omega = as_float(fm.side), as_float(fm.omega)
    rd0, vd0, _ = _desired_state(
        0.0, n, na, side, omega
    )  # start on the desired formation (+ x offsets)
    plant = DoubleIntegratorPlant(
        initial_position=rd0.at[:, 0].add(as_float(offset)),
        initial_velocity=vd0,
        disturbance=str(sc.disturbance.acceleration),
        zoh=not continuous,
    )
    noisy = sc.noise.sigma_position > 0 or sc.noise.sigma_velocity > 0
    sensors = ChainRelativeSensors(
        count=n,
        n_axes=na,
        position_noise_std=as_float(sc.noise.sigma_position),
        velocity_noise_std=as_float(sc.noise.sigma_velocity),
        noisy=noisy,
    )
    supervisor = HierarchicalSupervisor(
        count=n,
        n_axes=na,
        dt=float(dt),
        side=side,
        omega=omega,
        e_s=as_float(sc.supervisor.e_s),
        k_estimated=jnp.asarray(k_est, jnp.int64),
        confirm_steps=jnp.asarray(round(sc.supervisor.confirm_time / dt), jnp.int64),
        monitor_start=jnp.asarray(round(sc.supervisor.monitor_start / dt), jnp.int64),
        flfr_enabled=jnp.asarray(bool(sc.supervisor.flfr and sc.fault.enabled)),
    )
    controller = ChainLlfrController(
        lambda0=as_float(sc.controller.lambda0),
        lambda1=as_float(sc.controller.lambda1),
        alpha=as_float(sc.allocation.alpha),
        alpha_flfr=as_float(alpha_flfr(sc)),
        b_nominal=as_float(b_nom),
        b_hat=as_float(b_hat),
        side=side,
        omega=omega,
        fault_index=sc.fault.satellite - 1,
        is_sampled=not continuous,
    )
    actuator = StepGainActuator(
        gain=as_float(b_nom), faulty_gain=as_float(b_true(sc)), onset=as_float(k_onset * dt)
    )
    settle_steps = round(sc.supervisor.settle_time / dt)
    evaluations = (
        ChainTrackingError(),
        ThresholdFlag(
            name="flfr_settled",
            source="time_in_flfr",
            threshold=as_float((settle_steps + 0.5) * dt),
            long_name="FLFR active for longer than supervisor.settle_time",
        ),
    )
    metrics = [
        Metric(
            "max_err",
            "tracking_error",
            reduce="max",
            norm=True,
            norm_ord="inf",
            spacecraft="max",
            units="m",
        ),
        Metric(
            "max_err_x",
            "tracking_error",
            reduce="max",
            norm=True,
            component=0,
            spacecraft="max",
            units="m",
        ),
        Metric(
            "max_err_after_flfr",
            "tracking_error",
            reduce="max",
            norm=True,
            norm_ord="inf",
            spacecraft="max",
            units="m",
            gate="flfr_settled",
        ),
        Metric("t_flfr", "mode", reduce="first", threshold=as_float(FLFR), units="s"),
        Metric("n_events", "mode_changes", reduce="final"),
        Metric(
            "effort_x", "effort", reduce="final", component=0, spacecraft="each", units="m2 s-3"
        ),
    ]
    if sim.horizon >= EFFORT_TIME - 1e-9:
        metrics.append(
            Metric(
                "effort_x_100s",
                "effort",
                reduce="at",
                start=as_float(EFFORT_TIME),
                component=0,
                spacecraft="each",
                units="m2 s-3",
            )
        )
    return ClosedLoop.from_simulation(
        sim,
        plant=plant,
        controller=controller,
        sensors=sensors,
        supervisor=supervisor,
        actuator=actuator,
        evaluations=evaluations,
        metrics=tuple(metrics),
    )


def _dataset_attrs(sc: Azizi2009Scenario, loop: ClosedLoop) -> dict[str, float]:
    a_f = float(
        np.asarray(cast(ChainLlfrController, loop.controller).alpha_flfr)
    )  # make_loop's controller
    d_llfr, d_flfr = d_norms(sc, sc.allocation.alpha, a_f)
    return {"alpha_flfr": a_f, "D_norm_llfr": d_llfr, "D_norm_flfr": d_flfr}


def build(sc: Azizi2009Scenario) -> Compiled:
    """Compile a scenario: the composition of :func:`make_loop`; the dataset carries the FLFR weight and
    ||D||_2 of eq. (6) at the LLFR and FLFR weights (true eps) as attributes."""
    loop = make_loop(sc)
    return compile_loop(loop, dataset_attrs=_dataset_attrs(sc, loop))


# --------------------------------------------------------------------------------------------------
# running: one scenario, or a batch of variations of one scenario (one compiled program)
# --------------------------------------------------------------------------------------------------
def load(
    name_or_path: str | Path, overrides: Mapping[str, Any] | Iterable[str] | None = None
) -> Azizi2009Scenario:
    """Built-in scenario name or TOML path (+ overrides) -> validated :class:`Azizi2009Scenario`."""
    from formation_ftc.api import load_scenario

    sc = load_scenario(name_or_path, overrides)
    if not isinstance(sc, Azizi2009Scenario):
        raise loader.ScenarioError(
            f"{name_or_path}: scenario.method must be 'azizi2009', got {sc.scenario.method!r}"
        )
    return sc


#: what :func:`run_batch` may vary: name -> (component, field) of the closed loop (None: the loop)
VARIABLE = {
    "alpha": ("controller", "alpha"),
    "alpha_flfr": ("controller", "alpha_flfr"),
    "seed": (None, "seed"),
}


def _variant(loop: ClosedLoop, values: Mapping[str, Any]) -> ClosedLoop:
    for name, value in values.items():
        slot, field = VARIABLE[name]
        old = getattr(loop, field) if slot is None else getattr(getattr(loop, slot), field)
        new = jnp.asarray(value, dtype=jnp.result_type(old))
        change: dict[str, Any] = {field: new}
        if slot is None:
            loop = dataclasses.replace(loop, **change)
        else:
            loop = dataclasses.replace(
                loop, **{slot: dataclasses.replace(getattr(loop, slot), **change)}
            )
    return loop


def run_batch(
    sc: Azizi2009Scenario, variations: Mapping[str, np.ndarray], grid: tuple[int, int] | None = None
) -> list[dict[str, float]]:
    """Metrics of len(batch) runs of ``sc`` that differ only in the given leaves (see :data:`VARIABLE`:
    ``alpha`` (B, N), ``alpha_flfr`` (B,), ``seed`` (B,)), run as one compiled, vmapped program through
    :mod:`formation_ftc.sim.batch` (leaves shared by every run stay unbatched). Each run's metrics also
    carry ``D_norm_llfr`` / ``D_norm_flfr``: ||D||_2 of eq. (6) from its weights (true eps).

    ``grid = (rows, columns)``: run b is cell ``(b // columns, b % columns)`` of a grid (B = rows x
    columns), batched by two nested maps (:func:`formation_ftc.sim.batch.stack_params_grid`): a leaf
    that changes only from row to row -- a seed per row -- is batched once per row, and so is the work
    that depends on it alone (the noise draws). Same metrics, in the same order.
    Raises ``RuntimeError`` naming a run that diverged."""
    unknown = set(variations) - set(VARIABLE)
    if unknown:
        raise KeyError(f"unknown variations {sorted(unknown)}; valid: {sorted(VARIABLE)}")
    sizes = {np.asarray(v).shape[0] for v in variations.values()}
    if len(sizes) != 1:
        raise ValueError(f"all variations need the same batch size, got {sizes}")
    (size,) = sizes
    loop = make_loop(sc)
    compiled = compile_loop(loop)
    loops = [
        _variant(loop, {k: np.asarray(v)[b] for k, v in variations.items()}) for b in range(size)
    ]
    if grid is None:
        batch, axes = stack_params(loops)
        out = jax.device_get(batched_run(compiled, axes, size)(batch))
    else:
        rows, cols = (int(g) for g in grid)
        if rows < 1 or cols < 1 or rows * cols != size:
            raise ValueError(f"grid = {grid}: rows x columns must equal the batch size {size}")
        batch, row_axes, col_axes = stack_params_grid(
            [loops[r * cols : (r + 1) * cols] for r in range(rows)]
        )
        out = jax.device_get(batched_grid_run(compiled, row_axes, col_axes, rows, cols)(batch))
        out = jax.tree_util.tree_map(lambda a: np.reshape(a, (size,) + np.shape(a)[2:]), out)
    res = []
    for b, lp in enumerate(loops):
        div = int(out["diverged_step"][b])
        if div >= 0:
            raise RuntimeError(f"batch member {b} diverged at step {div}")
        m = metrics_dict(loop.metrics, [np.asarray(v)[b] for v in out["metrics"]])
        ctl = cast(ChainLlfrController, lp.controller)  # make_loop's controller
        m["D_norm_llfr"], m["D_norm_flfr"] = d_norms(
            sc, np.asarray(ctl.alpha), float(np.asarray(ctl.alpha_flfr))
        )
        res.append(m)
    return res


def simulate(sc: Azizi2009Scenario):
    """One run -> (xarray.Dataset with provenance, metrics dict); raises SimulationDiverged."""
    from formation_ftc.api import simulate_with_metrics

    return simulate_with_metrics(sc)


def plot(ds, sc: Azizi2009Scenario, out_dir: Path) -> list[Path]:
    """Tracking errors and cumulative efforts of one run (x axis), with the mode and e_s."""
    from formation_ftc.papers.azizi2009.figures import plot_run

    return plot_run(ds, sc, Path(out_dir))


METHOD = register_method(
    Method(
        name="azizi2009",
        schema=Azizi2009Scenario,
        build=build,
        description="Azizi & Khorasani 2009: deep-space double integrators, LLFR allocation, HL supervisor, FLFR",
        check=check,
        plot=plot,
    )
)
