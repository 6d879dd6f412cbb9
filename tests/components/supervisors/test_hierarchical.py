"""Supervisor ``hierarchical``: the HL supervisor's fault information from the estimator in the loop
(``fault_information = "estimator"``): Nominal -> LLFR at the first step the estimate reports ``detected``, the scripted mode
unchanged, the chain errors formed on board from an (N, 6) relative state, and the errors on an
estimator that gives no detection; the machine's Nominal -> LLFR -> FLFR guards, dwell counter,
mode-change and FLFR-time counters, branch-free under jit/vmap/scan. Truth: the switch steps follow
from hand-built input sequences."""

from __future__ import annotations

import copy

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components.supervisors.hierarchical import (
    FLFR,
    LLFR,
    NOMINAL,
    HierarchicalSupervisor,
    initial_state,
    transition,
)
from formation_ftc.config import loader
from formation_ftc.config.loader import ScenarioError
from formation_ftc.core.polygon_formation import chain_difference, rotating_polygon
from formation_ftc.sim.components import CompositionError, FlightInputs, StepContext

DT, N, AXES, SIDE, OMEGA = 0.5, 4, 2, 200.0, 0.1


def _sup(**kw) -> HierarchicalSupervisor:
    fields = dict(
        count=N,
        n_axes=AXES,
        side=jnp.asarray(SIDE),
        omega=jnp.asarray(OMEGA),
        e_s=jnp.asarray(0.03),
        k_estimated=jnp.asarray(2, jnp.int64),
        confirm_steps=jnp.asarray(1, jnp.int64),
        monitor_start=jnp.asarray(0, jnp.int64),
        flfr=jnp.asarray(True),
    )
    return HierarchicalSupervisor(**{**fields, **kw})


def _step(k):
    """The context of step k (t_k = k DT)."""
    k = jnp.asarray(k, dtype=jnp.int64)
    return StepContext(k, k * DT, DT)


def _chain_measurement(t, err):
    rd, _, _ = rotating_polygon(t, N, AXES, SIDE, OMEGA)
    return {
        "position": chain_difference(rd).at[1, 0].add(err),
        "velocity": jnp.zeros((N - 1, AXES)),
    }


def _state_measurement(t, err):
    """(N, 6) relative state whose chain pair (2, 3) is off by ``err`` on the first axis."""
    rd, _, _ = rotating_polygon(t, N, AXES, SIDE, OMEGA)
    q = jnp.zeros((N, 6)).at[:, :AXES].set(rd)
    return q.at[2:, 0].add(err)  # spacecraft 3 and 4 shifted: only the pair (2, 3) changes


def _fly(sup, errors, detected, measure=_chain_measurement):
    """Modes per step for the chain errors ``errors`` and the estimates ``detected`` (None: none)."""
    state = sup.initial_state()
    modes = []
    for k, (err, det) in enumerate(zip(errors, detected, strict=True)):
        t = jnp.asarray(k * DT)
        est = None if det is None else {"detected": jnp.asarray(det), "isolated": jnp.zeros((N, 3))}
        state, dec = sup.update(
            t, state, FlightInputs(measure(t, err), None, est, None, None, None, _step(k))
        )
        modes.append(int(dec))
    return modes, state


def test_estimator_mode_switches_at_the_first_detection():
    errs = [0.1, 0.1, 0.0, 0.0, 0.0, 0.05, 0.0]
    det = [False, False, False, False, True, True, True]  # the FDI's latched alarm from k = 4
    modes, state = _fly(_sup(fault_information="estimator"), errs, det)
    # the scripted k_estimated = 2 is ignored; LLFR at k = 4; 0.05 > e_s at k = 5 -> FLFR
    assert modes == [NOMINAL] * 4 + [LLFR] + [FLFR] * 2
    assert int(state.mode_changes) == 2
    # a per-spacecraft detection (N,) also counts ("any spacecraft"); a one-step alarm latches LLFR
    det_n = [np.zeros(N, bool)] * 3 + [np.eye(N, dtype=bool)[2]] + [np.zeros(N, bool)] * 3
    modes, _ = _fly(_sup(fault_information="estimator"), [0.0] * 7, det_n)
    assert modes == [NOMINAL] * 3 + [LLFR] * 4


def test_estimator_mode_never_switches_without_a_detection():
    modes, state = _fly(_sup(fault_information="estimator"), [0.1] * 6, [False] * 6)
    assert modes == [NOMINAL] * 6 and int(state.mode_changes) == 0


def test_scripted_mode_ignores_the_estimate_and_is_unchanged():
    errs = [0.1, 0.1, 0.0, 0.02, 0.05, 0.0]
    ref, _ = _fly(_sup(), errs, [None] * 6)  # the paper's test sequence
    assert ref == [NOMINAL, NOMINAL, LLFR, LLFR, FLFR, FLFR]
    with_est, _ = _fly(_sup(), errs, [True] * 6)  # an estimate in the loop changes nothing
    assert with_est == ref


def test_estimator_mode_under_jit_equals_eager():
    sup = _sup(fault_information="estimator")
    errs = [0.0, 0.0, 0.0, 0.1, 0.1]
    det = [False, True, True, True, True]
    eager, _ = _fly(sup, errs, det)

    @jax.jit
    def step(state, k, err, d):
        sc = _step(k)
        est = {"detected": d}
        return sup.update(
            sc.t, state, FlightInputs(_chain_measurement(sc.t, err), None, est, *[None] * 3, sc)
        )

    state, jitted = sup.initial_state(), []
    for k, (e, d) in enumerate(zip(errs, det, strict=True)):
        state, dec = step(state, jnp.asarray(k), jnp.asarray(e), jnp.asarray(d))
        jitted.append(int(dec))
    assert jitted == eager == [NOMINAL, LLFR, LLFR, FLFR, FLFR]


def test_on_board_chain_from_the_relative_state_equals_the_chain_measurement():
    errs = [0.1, 0.1, 0.0, 0.02, 0.05, 0.0]
    chain, _ = _fly(_sup(), errs, [None] * 6)
    on_board, _ = _fly(_sup(), errs, [None] * 6, _state_measurement)
    assert on_board == chain == [NOMINAL, NOMINAL, LLFR, LLFR, FLFR, FLFR]


def test_estimator_mode_without_a_detected_estimate_is_a_composition_error():
    sup = _sup(fault_information="estimator")
    y = _chain_measurement(0.0, 0.0)
    for est in (None, {"statistic": jnp.zeros((N, 3))}):
        with pytest.raises(CompositionError, match="fault_information = 'estimator'"):
            sup.update(
                0.0, sup.initial_state(), FlightInputs(y, None, est, None, None, None, _step(0))
            )
    with pytest.raises(CompositionError, match="fault_information = 'oracle'"):
        _sup(fault_information="oracle")


# ------------------------------------------------------------------------------ the machine (Sec. I-IV)
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
        flfr=jnp.asarray(True),
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


# ------------------------------------------------------------------------------ composed scenarios
def _composed(**slots):
    raw = copy.deepcopy(loader.read_raw("compose-azizi2009-on-li2020")[0])
    raw["supervisor"]["fault_information"] = "estimator"
    raw.update(slots)
    return raw


def test_composed_estimator_mode_needs_an_estimator_with_detected():
    with pytest.raises(ScenarioError) as err:
        ftc.load_scenario(_composed())
    msg = str(err.value)
    assert "supervisor hierarchical needs an estimate that reports a fault detection" in msg, msg
    assert "supervisor.fault_information = 'estimator'" in msg and 'type = "residual-fdi"' in msg
    # an estimator whose estimate has no 'detected' (a navigation filter) is refused as well
    nav = {
        "type": "relative-navigation-filter",
        "semi_major_axis": 7000e3,
        "position_noise_std": 0.1,
        "velocity_noise_std": 0.001,
    }
    with pytest.raises(ScenarioError, match="supervisor.fault_information = 'estimator'"):
        ftc.load_scenario(_composed(estimator=nav))


@pytest.mark.slow  # one compiled loop (~20 s, mostly compilation)
def test_composed_loop_switches_at_the_fdi_alarm_step():
    """Azizi2009's loop on Li2020's plant with the LVLH relative-state sensors (chain outputs formed on
    board), a residual FDI and the supervisor in estimator mode: the recorded mode leaves Nominal at
    the FDI's first recorded alarm, not at the scripted estimate_time."""
    fdi = {
        "type": "residual-fdi",
        "semi_major_axis": 7000e3,
        "position_noise_std": 0.1,
        "velocity_noise_std": 0.001,
        "nominal_mass": [100.0, 120.0, 115.0, 108.0],
    }
    raw = _composed(
        sensors={"type": "lvlh-relative-state"}, estimator=fdi, metrics=[], evaluations=[]
    )
    raw["simulation"].update(horizon=3.0, dt=0.1, record_every=1)
    raw["supervisor"]["estimate_time"] = 2.5  # ignored in estimator mode
    ds, _ = ftc.simulate_with_metrics(ftc.load_scenario(raw))
    detected = ds["fdi_detected"].values > 0.5
    mode = ds["mode"].values
    # the acquisition from Li2020's spread-out start is far outside the CW model: an early alarm
    assert detected.any()
    k = int(np.argmax(detected))
    assert 0 < k < 25  # before the scripted 2.5 s
    assert (mode[:k] == NOMINAL).all() and (mode[k:] == LLFR).all()
