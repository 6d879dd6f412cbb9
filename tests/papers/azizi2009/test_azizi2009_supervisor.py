"""HL supervisor (blocks.supervisors.hierarchical_supervisor and its Supervisor component): Nominal ->
LLFR -> FLFR guards, the dwell (confirmation) counter, the mode-change and FLFR-time counters, and
branch-free execution under jit/vmap/scan. Truth: the transition steps follow from the input sequence
by hand."""

import jax
import jax.numpy as jnp
import numpy as np

from formation_ftc.blocks.supervisors.hierarchical_supervisor import (
    FLFR,
    LLFR,
    NOMINAL,
    initial_state,
    transition,
)
from formation_ftc.components.supervisors.hierarchical import HierarchicalSupervisor
from formation_ftc.core.polygon_formation import chain_difference, rotating_polygon
from formation_ftc.sim.components import FlightInputs, StepContext


def _run(errors, k_est=3, e_s=0.03, confirm=2, monitor=0, enabled=True):
    def body(s, inp):
        k, e = inp
        s = transition(s, k, e, k_est, e_s, confirm, monitor, enabled, 0.5)
        return s, (s.mode, s.mode_changes, s.flfr_steps)

    ks = jnp.arange(len(errors), dtype=jnp.int64)
    return jax.jit(lambda e: jax.lax.scan(body, initial_state(), (ks, e)))(jnp.asarray(errors))


def test_transitions_and_counters():
    err = [0.0, 0.05, 0.0, 0.0, 0.04, 0.0, 0.04, 0.04, 0.04, 0.0]
    final, (modes, changes, flfr_steps) = _run(err)
    # LLFR at k = 3 (estimate); violation at 4 alone is not confirmed; 6 and 7 confirm -> FLFR at 7
    assert modes.tolist() == [NOMINAL] * 3 + [LLFR] * 4 + [FLFR] * 3
    assert changes.tolist() == [0, 0, 0, 1, 1, 1, 1, 2, 2, 2]
    assert flfr_steps.tolist() == [0] * 7 + [1, 2, 3]  # the switch step counts as the first
    assert int(final.mode_changes) == 2


def test_no_flfr_when_disabled_or_before_monitoring():
    final, (modes, _, _) = _run([0.1] * 8, k_est=0, enabled=False)
    assert modes.tolist() == [LLFR] * 8 and int(final.mode_changes) == 1
    _, (modes, _, _) = _run([0.1] * 8, k_est=0, monitor=5, confirm=1)
    assert modes.tolist() == [LLFR] * 5 + [FLFR] * 3


def test_vmap_batched_equals_single():
    errs = np.array([[0.0, 0.1, 0.1, 0.1, 0.1], [0.0, 0.0, 0.0, 0.0, 0.0]])
    _, (modes_b, _, _) = jax.vmap(lambda e: _run(e, k_est=0, confirm=2))(jnp.asarray(errs))
    for j in range(2):
        _, (m, _, _) = _run(errs[j], k_est=0, confirm=2)
        np.testing.assert_array_equal(modes_b[j], m)


def test_component_uniform_signature_reads_the_measured_error():
    """update(t, state, FlightInputs): the monitored error is the measured chain position minus the
    desired chain offsets; the step index comes with the step context; records counters and FLFR time."""
    dt, n = 0.5, 4
    sup = HierarchicalSupervisor(
        count=n,
        n_axes=2,
        side=jnp.asarray(200.0),
        omega=jnp.asarray(0.1),
        e_s=jnp.asarray(0.03),
        k_estimated=jnp.asarray(2, jnp.int64),
        confirm_steps=jnp.asarray(1, jnp.int64),
        monitor_start=jnp.asarray(0, jnp.int64),
        flfr_enabled=jnp.asarray(True),
    )
    state = sup.initial_state()
    modes, times = [], []
    for k, err in enumerate([0.1, 0.1, 0.0, 0.02, 0.05, 0.0]):
        t = jnp.asarray(k * dt)
        rd, _, _ = rotating_polygon(t, n, 2, 200.0, 0.1)
        y = {"position": chain_difference(rd).at[1, 0].add(err), "velocity": jnp.zeros((n - 1, 2))}
        sc = StepContext(jnp.asarray(k), t, dt)
        state, dec = sup.update(t, state, FlightInputs(y, None, None, None, None, None, sc))
        out = sup.outputs(t, state, dec)
        modes.append(int(dec))
        times.append(float(out["time_in_flfr"]))
    # estimate at k = 2 (errors before are ignored in Nominal); 0.05 > e_s at k = 4 -> FLFR
    assert modes == [NOMINAL, NOMINAL, LLFR, LLFR, FLFR, FLFR]
    assert times == [0.0, 0.0, 0.0, 0.0, 0.5, 1.0]
    assert int(sup.outputs(0.0, state, None)["mode_changes"]) == 2
