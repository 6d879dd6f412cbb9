"""Records show the supervisor's decision in force over the step (taken at t_k), as the metrics do.

A toy supervisor latches mode 1 at step ``SWITCH``; the controller's gain depends on the mode. With a
record at every step, the recorded mode and command at t_k must equal the in-run metric samples at t_k
(``at`` metrics, one per step) and the command must be the one that moved the plant over
[t_k, t_{k+1}) (exact double-integrator step, checked in numpy). Before the fix the record at the
switch step showed the mode before the decision (one step late) and a command computed with it.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

import formation_ftc  # noqa: F401  (x64)
from formation_ftc.components.plants.double_integrator import DoubleIntegratorPlant
from formation_ftc.sim.components import (
    Controller,
    FlightInputs,
    Signal,
    Supervisor,
    component,
    static,
)
from formation_ftc.sim.loop import ClosedLoop
from formation_ftc.sim.metrics import Metric

DT = 0.5  # [s]
N_STEPS = 12
SWITCH = 5  # step of the decision


@component
class LatchSupervisor(Supervisor):
    """Mode 0 until step ``switch`` (an int leaf, read against the step context's index), then 1 for
    good (latched in the state)."""

    switch: Any = 0

    def initial_state(self):
        return {"mode": jnp.asarray(0, dtype=jnp.int64), "changes": jnp.asarray(0, dtype=jnp.int64)}

    def update(self, t, state, inputs: FlightInputs):
        mode = jnp.where(inputs.step.k >= self.switch, 1, state["mode"])
        new = {"mode": mode, "changes": state["changes"] + (mode != state["mode"])}
        return new, new["mode"]

    def signals(self):
        return (
            Signal("mode", (), "1", "mode in force over [t_k, t_k+1) (decision taken at t_k)"),
            Signal("mode_changes", (), "1", "mode changes up to t_k, the decision at t_k included"),
        )

    def outputs(self, t, state, decision):
        return {
            "mode": decision.astype(jnp.float64),
            "mode_changes": state["changes"].astype(jnp.float64),
        }


@component
class ModeGainController(Controller):
    """u = -(1 + 2 mode) r [m/s^2]: the command shows which decision it was computed with."""

    count: int = static()
    quantity = "acceleration"

    def output(self, t, state, inputs: FlightInputs):
        gain = 1.0 + 2.0 * jnp.asarray(inputs.decision, dtype=jnp.float64)
        return -gain * inputs.measurement["r"], None, {}


def _loop(record_every: int) -> ClosedLoop:
    at = [
        Metric(f"{sig}_at_{k}", sig, reduce="at", start=float(k * DT), **kw)
        for k in range(N_STEPS + 1)
        for sig, kw in (
            ("mode", {}),
            ("mode_changes", {}),
            ("command", {"norm": True, "spacecraft": "max"}),
        )
    ]
    return ClosedLoop(
        plant=DoubleIntegratorPlant(
            initial_position=jnp.array([[1.0]]), initial_velocity=jnp.array([[0.0]])
        ),
        controller=ModeGainController(count=1),
        supervisor=LatchSupervisor(switch=jnp.asarray(SWITCH)),
        metrics=tuple(at) + (Metric("t_switch", "mode", reduce="first", threshold=1.0),),
        dt=DT,
        n_steps=N_STEPS,
        record_every=record_every,
    )


def _run(record_every: int):
    """(records as a Dataset, metrics) of one run."""
    compiled = _loop(record_every).validate()
    out = jax.tree_util.tree_map(np.asarray, compiled.run())
    assert int(out["diverged_step"]) == -1
    return compiled.dataset(out, N_STEPS // record_every + 1), compiled.metric_values(out)


def test_recorded_mode_is_the_decision_in_force():
    ds, m = _run(1)
    mode = ds["mode"].values
    assert ds.time.size == N_STEPS + 1
    np.testing.assert_array_equal(mode, (np.arange(N_STEPS + 1) >= SWITCH).astype(float))
    assert m["t_switch"] == SWITCH * DT
    for k in range(N_STEPS + 1):  # the record at t_k is the step's metric sample at t_k
        assert mode[k] == m[f"mode_at_{k}"], k
        assert ds["mode_changes"].values[k] == m[f"mode_changes_at_{k}"], k
        assert abs(ds["command"].values[k, 0, 0]) == m[f"command_at_{k}"], k
    # the recorded command moved the plant over [t_k, t_{k+1}) (exact step with the acceleration held)
    r, v, u = (
        ds["position"].values[:, 0, 0],
        ds["velocity"].values[:, 0, 0],
        ds["command"].values[:, 0, 0],
    )
    np.testing.assert_allclose(
        r[1:], r[:-1] + DT * v[:-1] + 0.5 * DT**2 * u[:-1], rtol=1e-13, atol=1e-15
    )
    np.testing.assert_allclose(u, -(1.0 + 2.0 * mode) * r, rtol=1e-15)
    # decimated records are samples of the same signal
    ds3, m3 = _run(3)
    np.testing.assert_array_equal(ds3["mode"].values, mode[::3])
    assert m3 == m
