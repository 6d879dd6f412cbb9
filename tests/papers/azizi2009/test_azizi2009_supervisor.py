"""HL supervisor (blocks.supervisors.hierarchical_supervisor): Nominal -> LLFR -> FLFR guards, the
dwell (confirmation) counter, the event log, and branch-free execution under jit/vmap/scan.
Truth: the transition times follow from the input sequence by hand."""

import jax
import jax.numpy as jnp
import numpy as np

from formation_ftc.blocks.supervisors.hierarchical_supervisor import (
    FLFR,
    LLFR,
    NOMINAL,
    HierarchicalSupervisor,
    events,
)

SUP = HierarchicalSupervisor()


def _run(errors, k_est=3, e_s=0.03, confirm=2, monitor=0, enabled=True):
    def body(s, inp):
        k, e = inp
        s = SUP.step(s, k, e, k_estimated=k_est, e_s=e_s, confirm_steps=confirm, monitor_start=monitor,
                     flfr_enabled=enabled)
        return s, s.mode

    ks = jnp.arange(len(errors), dtype=jnp.int64)
    return jax.jit(lambda e: jax.lax.scan(body, SUP.init(), (ks, e)))(jnp.asarray(errors))


def test_transitions_and_event_log():
    err = [0.0, 0.05, 0.0, 0.0, 0.04, 0.0, 0.04, 0.04, 0.04, 0.0]
    final, modes = _run(err)
    # LLFR at k = 3 (estimate); violation at 4 alone is not confirmed; 6 and 7 confirm -> FLFR at 7
    assert modes.tolist() == [NOMINAL] * 3 + [LLFR] * 4 + [FLFR] * 3
    ev = events(final, dt=0.5)
    assert ev == [{"step": 3, "time": 1.5, "from": "Nominal", "to": "LLFR"},
                  {"step": 7, "time": 3.5, "from": "LLFR", "to": "FLFR"}]


def test_no_flfr_when_disabled_or_before_monitoring():
    final, modes = _run([0.1] * 8, k_est=0, enabled=False)
    assert modes.tolist() == [LLFR] * 8 and int(final.n_events) == 1
    _, modes = _run([0.1] * 8, k_est=0, monitor=5, confirm=1)
    assert modes.tolist() == [LLFR] * 5 + [FLFR] * 3


def test_vmap_batched_equals_single():
    errs = np.array([[0.0, 0.1, 0.1, 0.1, 0.1], [0.0, 0.0, 0.0, 0.0, 0.0]])
    _, modes_b = jax.vmap(lambda e: _run(e, k_est=0, confirm=2))(jnp.asarray(errs))
    for j in range(2):
        _, m = _run(errs[j], k_est=0, confirm=2)
        np.testing.assert_array_equal(modes_b[j], m)
